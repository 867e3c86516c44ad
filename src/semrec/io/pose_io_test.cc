#include "semrec/io/pose_io.h"

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/testing/test_util.h"

namespace semrec::io {
namespace {

TEST(PoseIo, RedwoodLogRoundTrip) {
  semrec::testing::TempDir dir;
  std::vector<Transform> poses = {
      Transform(),
      Transform(
          Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()).toRotationMatrix(),
          {1, 2, 3})};
  WriteRedwoodLog(dir / "t.log", poses);
  const auto read = ReadRedwoodLog(dir / "t.log");
  ASSERT_EQ(read.size(), 2u);
  EXPECT_TRUE(read[1].IsApprox(poses[1], 1e-12));
}

TEST(PoseIo, TumTrajectoryQuaternionOrderIsXyzw) {
  semrec::testing::TempDir dir;
  // 90 degrees about z: q = (x, y, z, w) = (0, 0, sin 45, cos 45).
  semrec::testing::WriteText(dir / "gt.txt",
                             "# timestamp tx ty tz qx qy qz qw\n"
                             "2.0 0 0 0 0 0 0 1\n"
                             "1.0 1 2 3 0 0 0.70710678118 0.70710678118\n");
  const auto poses = ReadTumTrajectory(dir / "gt.txt");
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_DOUBLE_EQ(poses[0].timestamp_s, 1.0);  // sorted by time
  const Eigen::Vector3d x_rotated =
      poses[0].T_world_camera.rotation() * Eigen::Vector3d::UnitX();
  EXPECT_TRUE(x_rotated.isApprox(Eigen::Vector3d::UnitY(), 1e-9));
  EXPECT_TRUE(
      poses[0].T_world_camera.translation().isApprox(Eigen::Vector3d(1, 2, 3)));
}

TEST(PoseIo, TumTrajectoryRoundTrip) {
  semrec::testing::TempDir dir;
  const std::vector<StampedPose> poses = {
      {1305031102.175304,
       Transform(
           Eigen::AngleAxisd(2.5, Eigen::Vector3d(1, -2, 0.5).normalized())
               .toRotationMatrix(),
           {1.25, -0.5, 3.0})},
      {1305031102.211214, Transform()}};
  WriteTumTrajectory(dir / "est.txt", poses);
  const auto read = ReadTumTrajectory(dir / "est.txt");
  ASSERT_EQ(read.size(), 2u);
  EXPECT_NEAR(read[0].timestamp_s, poses[0].timestamp_s, 1e-6);
  EXPECT_TRUE(read[0].T_world_camera.IsApprox(poses[0].T_world_camera, 1e-7));
  EXPECT_TRUE(read[1].T_world_camera.IsApprox(Transform(), 1e-12));
}

TEST(PoseIo, IntrinsicsFiles) {
  semrec::testing::TempDir dir;
  semrec::testing::WriteText(
      dir / "k.json",
      R"({"width": 640, "height": 480, "intrinsic_matrix": [525.0, 0, 0, 0, 520.0, 0, 319.5, 239.5, 1]})");
  const CameraIntrinsics a = ReadOpen3dIntrinsics(dir / "k.json");
  EXPECT_EQ(a, (CameraIntrinsics{640, 480, 525.0, 520.0, 319.5, 239.5}));
  semrec::testing::WriteText(dir / "k.txt", "585 0 320\n0 586 240\n0 0 1\n");
  const CameraIntrinsics b = ReadIntrinsicsMatrixFile(dir / "k.txt", 640, 480);
  EXPECT_EQ(b, (CameraIntrinsics{640, 480, 585.0, 586.0, 320.0, 240.0}));
}

// T_world_camera = pre * T_file * post, lists multiplied left to right, a
// scaled 3x3 block replaced by its rotation (or refused when asked), bad
// entries named.
TEST(PoseIo, PoseCorrection) {
  semrec::testing::TempDir dir;
  semrec::testing::WriteText(dir / "c.yaml",
                             "pre: [[-1,0,0,0],[0,0,1,0],[0,1,0,0],[0,0,0,1]]\n"
                             "post:\n"
                             "  - [[1,0,0,1],[0,1,0,0],[0,0,1,0],[0,0,0,1]]\n"
                             "  - [[2,0,0,0],[0,2,0,0],[0,0,2,0],[0,0,0,1]]\n");
  const PoseCorrection c = ReadPoseCorrection(dir / "c.yaml");
  const Transform T_file(
      Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()).toRotationMatrix(),
      {1, 2, 3});
  Eigen::Matrix4d pre, post = Eigen::Matrix4d::Identity();
  pre << -1, 0, 0, 0, 0, 0, 1, 0, 0, 1, 0, 0, 0, 0, 0, 1;
  post(0, 3) = 1;  // the scale of the second matrix is orthonormalised away
  const Eigen::Matrix4d expected = pre * T_file.Matrix() * post;
  EXPECT_TRUE(c.Apply(T_file).Matrix().isApprox(expected, 1e-12));
  // The whole chain keeps rotations rigid.
  const Eigen::Matrix3d R = c.Apply(T_file).rotation();
  EXPECT_NEAR((R * R.transpose() - Eigen::Matrix3d::Identity()).norm(), 0,
              1e-9);

  semrec::testing::WriteText(dir / "strict.yaml",
                             "orthonormalize: false\npost: "
                             "[[2,0,0,0],[0,2,0,0],[0,0,2,0],[0,0,0,1]]\n");
  EXPECT_THROW(ReadPoseCorrection(dir / "strict.yaml"), FormatError);
  semrec::testing::WriteText(dir / "bad.yaml", "pre: [[1,0,0],[0,1,0]]\n");
  try {
    ReadPoseCorrection(dir / "bad.yaml");
    FAIL() << "a 2x3 matrix was accepted";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("pre"), std::string::npos) << e.what();
  }
  semrec::testing::WriteText(dir / "key.yaml", "prefix: 1\n");
  EXPECT_THROW(ReadPoseCorrection(dir / "key.yaml"), FormatError);
  EXPECT_THROW(ReadPoseCorrection(dir / "missing.yaml"), IoError);
}

}  // namespace
}  // namespace semrec::io
