#include "semrec/eval/trajectory.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <tuple>

#include <fmt/format.h>
#include <Eigen/SVD>

#include "semrec/core/error.h"

namespace semrec::eval {
namespace {

double Rms(const std::vector<double>& values) {
  if (values.empty()) return 0.0;
  double sum = 0.0;
  for (const double v : values) sum += v * v;
  return std::sqrt(sum / static_cast<double>(values.size()));
}

}  // namespace

void TrajectoryOptions::Check() const {
  CheckArgument(
      std::isfinite(max_time_difference_s) && max_time_difference_s >= 0.0,
      "trajectory: the maximum time difference must be >= 0 s");
  CheckArgument(rpe_delta_frames >= 1,
                "trajectory: the RPE delta must be at least 1 frame");
}

std::vector<std::pair<size_t, size_t>> AssociateByTime(
    const std::vector<io::StampedPose>& estimate,
    const std::vector<io::StampedPose>& ground_truth, double max_dt_s) {
  // Candidates closest first; ties in index order (deterministic).
  std::vector<std::tuple<double, size_t, size_t>> candidates;
  for (size_t i = 0; i < estimate.size(); ++i) {
    const double t = estimate[i].timestamp_s;
    // ground_truth need not be sorted: a linear scan per pose is fine for
    // the thousands of poses of a recording.
    for (size_t j = 0; j < ground_truth.size(); ++j) {
      const double dt = std::abs(ground_truth[j].timestamp_s - t);
      if (dt <= max_dt_s) candidates.emplace_back(dt, i, j);
    }
  }
  std::stable_sort(candidates.begin(), candidates.end());
  std::vector<bool> used_estimate(estimate.size()),
      used_truth(ground_truth.size());
  std::vector<std::pair<size_t, size_t>> pairs;
  for (const auto& [dt, i, j] : candidates) {
    if (used_estimate[i] || used_truth[j]) continue;
    used_estimate[i] = used_truth[j] = true;
    pairs.emplace_back(i, j);
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

Transform AlignRigid(const std::vector<Eigen::Vector3d>& from,
                     const std::vector<Eigen::Vector3d>& to) {
  CheckArgument(from.size() == to.size(),
                fmt::format("AlignRigid: {} points to align with {}",
                            from.size(), to.size()));
  CheckArgument(from.size() >= 3,
                fmt::format("AlignRigid: needs at least 3 point pairs, got {}",
                            from.size()));
  const double n = static_cast<double>(from.size());
  Eigen::Vector3d mean_from = Eigen::Vector3d::Zero();
  Eigen::Vector3d mean_to = Eigen::Vector3d::Zero();
  for (size_t k = 0; k < from.size(); ++k) {
    mean_from += from[k];
    mean_to += to[k];
  }
  mean_from /= n;
  mean_to /= n;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (size_t k = 0; k < from.size(); ++k) {
    covariance += (to[k] - mean_to) * (from[k] - mean_from).transpose();
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(
      covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  // Umeyama's sign correction: a rotation, never a reflection.
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0) {
    S(2, 2) = -1.0;
  }
  const Eigen::Matrix3d R = svd.matrixU() * S * svd.matrixV().transpose();
  return Transform(R, mean_to - R * mean_from);
}

Transform AlignPoses(const std::vector<io::StampedPose>& estimate,
                     const std::vector<io::StampedPose>& ground_truth,
                     const TrajectoryOptions& options) {
  options.Check();
  std::vector<Eigen::Vector3d> from, to;
  for (const auto& [i, j] :
       AssociateByTime(estimate, ground_truth, options.max_time_difference_s)) {
    for (int axis = -1; axis < 3; ++axis) {
      const Eigen::Vector3d tip = axis < 0 ? Eigen::Vector3d::Zero().eval()
                                           : Eigen::Vector3d::Unit(axis).eval();
      from.push_back(estimate[i].T_world_camera * tip);
      to.push_back(ground_truth[j].T_world_camera * tip);
    }
  }
  CheckArgument(!from.empty(),
                "trajectory: no estimated pose has a ground-truth pose at its "
                "time: do the timestamps share a clock?");
  return AlignRigid(from, to);
}

TrajectoryErrors EvaluateTrajectory(
    const std::vector<io::StampedPose>& estimate,
    const std::vector<io::StampedPose>& ground_truth,
    const TrajectoryOptions& options) {
  options.Check();
  TrajectoryErrors out;
  out.pairs =
      AssociateByTime(estimate, ground_truth, options.max_time_difference_s);
  out.associated = out.pairs.size();
  out.unmatched_estimate = estimate.size() - out.associated;
  out.unmatched_ground_truth = ground_truth.size() - out.associated;
  CheckArgument(
      out.associated >= 3,
      fmt::format("trajectory: only {} of {} estimated poses have a "
                  "ground-truth pose within {} s (of {}); at least 3 are "
                  "needed: do the timestamps share a clock?",
                  out.associated, estimate.size(),
                  options.max_time_difference_s, ground_truth.size()));
  std::vector<Eigen::Vector3d> est_positions, gt_positions;
  for (const auto& [i, j] : out.pairs) {
    est_positions.push_back(estimate[i].T_world_camera.translation());
    gt_positions.push_back(ground_truth[j].T_world_camera.translation());
  }
  out.T_ground_truth_estimate = AlignRigid(est_positions, gt_positions);
  std::vector<double> distances;
  for (size_t k = 0; k < est_positions.size(); ++k) {
    distances.push_back(
        (out.T_ground_truth_estimate * est_positions[k] - gt_positions[k])
            .norm());
  }
  out.ate_rmse_m = Rms(distances);
  out.ate_mean_m = std::accumulate(distances.begin(), distances.end(), 0.0) /
                   static_cast<double>(distances.size());
  out.ate_max_m = *std::max_element(distances.begin(), distances.end());
  std::vector<double> sorted = distances;
  std::sort(sorted.begin(), sorted.end());
  const size_t m = sorted.size();
  out.ate_median_m =
      m % 2 == 1 ? sorted[m / 2] : 0.5 * (sorted[m / 2 - 1] + sorted[m / 2]);
  for (size_t k = 1; k < gt_positions.size(); ++k) {
    out.path_length_m += (gt_positions[k] - gt_positions[k - 1]).norm();
  }
  // RPE: E = (gt_a^-1 gt_b)^-1 (est_a^-1 est_b), as evaluate_rpe.py.
  std::vector<double> translation, rotation_deg;
  double moved_m = 0.0;
  for (size_t k = 0; k + options.rpe_delta_frames < out.pairs.size(); ++k) {
    const auto [ea, ga] = out.pairs[k];
    const auto [eb, gb] = out.pairs[k + options.rpe_delta_frames];
    const Transform gt_motion = ground_truth[ga].T_world_camera.Inverse() *
                                ground_truth[gb].T_world_camera;
    const Transform est_motion =
        estimate[ea].T_world_camera.Inverse() * estimate[eb].T_world_camera;
    const Transform error = gt_motion.Inverse() * est_motion;
    translation.push_back(error.translation().norm());
    rotation_deg.push_back(error.AngleDeg());
    moved_m += gt_motion.translation().norm();
  }
  out.rpe_pairs = translation.size();
  out.rpe_translation_rmse_m = Rms(translation);
  out.rpe_rotation_rmse_deg = Rms(rotation_deg);
  if (moved_m > 0.0) {
    out.rpe_translation_per_m =
        std::accumulate(translation.begin(), translation.end(), 0.0) / moved_m;
    out.rpe_rotation_deg_per_m =
        std::accumulate(rotation_deg.begin(), rotation_deg.end(), 0.0) /
        moved_m;
  }
  return out;
}

std::vector<io::StampedPose> ReadTrajectory(
    const std::filesystem::path& path,
    const io::SequenceReaderOptions& options) {
  if (std::filesystem::is_regular_file(path) &&
      options.pose_correction_path.empty()) {
    return io::ReadTumTrajectory(path);
  }
  const io::SequenceReader reader = io::SequenceReader::Open(path, options);
  CheckArgument(reader.index().has_poses,
                path.string() + ": the sequence has no poses to compare with");
  std::vector<io::StampedPose> poses;
  for (const io::FrameRecord& f : reader.index().frames) {
    poses.push_back({f.timestamp_s, f.T_world_camera});
  }
  return poses;
}

std::string TrajectoryErrorsText(const TrajectoryErrors& e) {
  std::string text = fmt::format(
      "{} poses associated ({} estimated and {} ground-truth poses without a "
      "partner), ground-truth path {:.3f} m\n",
      e.associated, e.unmatched_estimate, e.unmatched_ground_truth,
      e.path_length_m);
  text += fmt::format(
      "ATE (after rigid alignment): RMSE {:.4f} m, mean {:.4f} m, median "
      "{:.4f} m, max {:.4f} m\n",
      e.ate_rmse_m, e.ate_mean_m, e.ate_median_m, e.ate_max_m);
  text += fmt::format(
      "RPE over {} pairs: translation RMSE {:.4f} m, rotation RMSE {:.3f} "
      "deg; drift {:.4f} m/m, {:.3f} deg/m\n",
      e.rpe_pairs, e.rpe_translation_rmse_m, e.rpe_rotation_rmse_deg,
      e.rpe_translation_per_m, e.rpe_rotation_deg_per_m);
  return text;
}

nlohmann::json TrajectoryErrorsJson(const TrajectoryErrors& e) {
  return {{"associated", e.associated},
          {"unmatched_estimate", e.unmatched_estimate},
          {"unmatched_ground_truth", e.unmatched_ground_truth},
          {"path_length_m", e.path_length_m},
          {"ate_rmse_m", e.ate_rmse_m},
          {"ate_mean_m", e.ate_mean_m},
          {"ate_median_m", e.ate_median_m},
          {"ate_max_m", e.ate_max_m},
          {"rpe_pairs", e.rpe_pairs},
          {"rpe_translation_rmse_m", e.rpe_translation_rmse_m},
          {"rpe_rotation_rmse_deg", e.rpe_rotation_rmse_deg},
          {"rpe_translation_per_m", e.rpe_translation_per_m},
          {"rpe_rotation_deg_per_m", e.rpe_rotation_deg_per_m}};
}

}  // namespace semrec::eval
