#include "semrec/eval/trajectory.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "semrec/core/error.h"

namespace semrec::eval {
namespace {

io::StampedPose At(double t, const Eigen::Vector3d& p, double yaw_deg = 0.0) {
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ())
          .toRotationMatrix();
  return {t, Transform(R, p)};
}

TEST(Trajectory, AssociatesClosestFirstEachPoseOnce) {
  const std::vector<io::StampedPose> est = {
      At(1.000, {0, 0, 0}), At(1.010, {0, 0, 0}), At(2.000, {0, 0, 0})};
  const std::vector<io::StampedPose> gt = {At(1.008, {0, 0, 0}),
                                           At(1.030, {0, 0, 0})};
  // 1.010 <-> 1.008 (2 ms) goes first; 1.000 then takes 1.030 (30 ms) only
  // when that is allowed.
  const auto tight = AssociateByTime(est, gt, 0.02);
  ASSERT_EQ(tight.size(), 1u);
  EXPECT_EQ(tight[0], std::make_pair(size_t{1}, size_t{0}));
  const auto loose = AssociateByTime(est, gt, 0.05);
  ASSERT_EQ(loose.size(), 2u);
  EXPECT_EQ(loose[0], std::make_pair(size_t{0}, size_t{1}));
  EXPECT_EQ(loose[1], std::make_pair(size_t{1}, size_t{0}));
}

TEST(Trajectory, RigidlyMovedCopyHasNoError) {
  std::vector<io::StampedPose> gt, est;
  const Transform T(
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized())
          .toRotationMatrix(),
      Eigen::Vector3d(5, -2, 1));
  for (int i = 0; i < 20; ++i) {
    const io::StampedPose p =
        At(0.1 * i, {std::sin(0.3 * i), 0.1 * i, std::cos(0.2 * i)}, 3.0 * i);
    gt.push_back(p);
    est.push_back({p.timestamp_s, T * p.T_world_camera});
  }
  const TrajectoryErrors e = EvaluateTrajectory(est, gt);
  EXPECT_EQ(e.associated, 20u);
  EXPECT_NEAR(e.ate_rmse_m, 0.0, 1e-9);
  EXPECT_NEAR(e.rpe_translation_rmse_m, 0.0, 1e-9);
  EXPECT_NEAR(e.rpe_rotation_rmse_deg, 0.0, 1e-5);
  EXPECT_TRUE(e.T_ground_truth_estimate.IsApprox(T.Inverse(), 1e-9));
}

TEST(Trajectory, PosesAlignAStraightPathWithItsTurnAboutItself) {
  // A straight path gives the positions no hold on a turn about it; the
  // cameras' orientations do.
  std::vector<io::StampedPose> gt, est;
  const Transform T(
      Eigen::AngleAxisd(0.9, Eigen::Vector3d::UnitX()).toRotationMatrix(),
      Eigen::Vector3d(0.5, -1, 2));
  for (int i = 0; i < 10; ++i) {
    const io::StampedPose p = At(0.1 * i, {0.2 * i, 0, 0}, 5.0 * i);
    gt.push_back(p);
    est.push_back({p.timestamp_s, T * p.T_world_camera});
  }
  EXPECT_TRUE(AlignPoses(est, gt).IsApprox(T.Inverse(), 1e-9));
}

TEST(Trajectory, HandComputedOffsets) {
  // A straight path 1 m per frame; the estimate is off sideways by
  // +0.1, -0.1, -0.1, +0.1 m: no rigid motion removes that (the offsets'
  // mean is 0 and they do not correlate with the path), so every error is
  // 0.1 m. The steps' errors (estimate step - true step) are (0, -0.2, 0),
  // (0, 0, 0) and (0, 0.2, 0): RPE RMSE sqrt(0.08 / 3), 0.4 m over 3 m.
  const std::vector<io::StampedPose> gt = {At(0, {0, 0, 0}), At(1, {1, 0, 0}),
                                           At(2, {2, 0, 0}), At(3, {3, 0, 0})};
  const std::vector<io::StampedPose> est = {
      At(0, {0, 0.1, 0}), At(1, {1, -0.1, 0}), At(2, {2, -0.1, 0}),
      At(3, {3, 0.1, 0})};
  const TrajectoryErrors e = EvaluateTrajectory(est, gt);
  EXPECT_NEAR(e.ate_rmse_m, 0.1, 1e-9);
  EXPECT_NEAR(e.ate_mean_m, 0.1, 1e-9);
  EXPECT_NEAR(e.ate_median_m, 0.1, 1e-9);
  EXPECT_NEAR(e.ate_max_m, 0.1, 1e-9);
  EXPECT_NEAR(e.path_length_m, 3.0, 1e-12);
  EXPECT_EQ(e.rpe_pairs, 3u);
  EXPECT_NEAR(e.rpe_translation_rmse_m, std::sqrt(0.08 / 3.0), 1e-9);
  EXPECT_NEAR(e.rpe_translation_per_m, 0.4 / 3.0, 1e-9);
  EXPECT_NEAR(e.rpe_rotation_rmse_deg, 0.0, 1e-6);
}

TEST(Trajectory, DriftPerMetreAndPerDegree) {
  // The estimate overshoots every 1 m step by 10 cm and turns 2 degrees per
  // frame more than the ground truth (about its own optical axis, so the
  // positions stay comparable).
  std::vector<io::StampedPose> gt, est;
  for (int i = 0; i < 6; ++i) {
    gt.push_back(At(i, {1.0 * i, 0, 0}));
    est.push_back(At(i, {1.1 * i, 0, 0}, 2.0 * i));
  }
  TrajectoryOptions options;
  const TrajectoryErrors e = EvaluateTrajectory(est, gt, options);
  EXPECT_EQ(e.rpe_pairs, 5u);
  EXPECT_NEAR(e.rpe_rotation_rmse_deg, 2.0, 1e-6);
  EXPECT_NEAR(e.rpe_rotation_deg_per_m, 2.0, 1e-6);
  // Over 5 frames the turns add up.
  options.rpe_delta_frames = 5;
  const TrajectoryErrors whole = EvaluateTrajectory(est, gt, options);
  EXPECT_EQ(whole.rpe_pairs, 1u);
  EXPECT_NEAR(whole.rpe_rotation_rmse_deg, 10.0, 1e-6);
}

TEST(Trajectory, AlignmentIsALeastSquaresMinimum) {
  // Against a reference: no small rigid motion of the aligned estimate
  // lowers the squared error Horn's solution gives.
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.05);
  std::vector<Eigen::Vector3d> from, to;
  for (int i = 0; i < 30; ++i) {
    const Eigen::Vector3d p(std::cos(0.4 * i), std::sin(0.3 * i), 0.05 * i);
    from.push_back(p);
    to.push_back(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY()) * p +
                 Eigen::Vector3d(1, 2, 3) +
                 Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
  }
  const Transform T = AlignRigid(from, to);
  const auto cost = [&](const Transform& A) {
    double c = 0.0;
    for (size_t k = 0; k < from.size(); ++k) {
      c += (A * from[k] - to[k]).squaredNorm();
    }
    return c;
  };
  const double best = cost(T);
  for (int axis = 0; axis < 3; ++axis) {
    for (const double step : {-1e-3, 1e-3}) {
      const Eigen::Vector3d unit = Eigen::Vector3d::Unit(axis);
      const Transform turned(
          Eigen::AngleAxisd(step, unit).toRotationMatrix() * T.rotation(),
          T.translation());
      const Transform shifted(T.rotation(), T.translation() + step * unit);
      EXPECT_GT(cost(turned), best);
      EXPECT_GT(cost(shifted), best);
    }
  }
}

TEST(Trajectory, TooFewAssociatedPosesIsAClearError) {
  const std::vector<io::StampedPose> gt = {At(0, {0, 0, 0}), At(1, {1, 0, 0}),
                                           At(2, {2, 0, 0})};
  const std::vector<io::StampedPose> est = {
      At(100, {0, 0, 0}), At(101, {1, 0, 0}), At(102, {2, 0, 0})};
  try {
    EvaluateTrajectory(est, gt);
    FAIL() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("only 0 of 3"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace semrec::eval
