// Trajectory accuracy as the TUM RGB-D benchmark measures it (Sturm et al.,
// IROS 2012; its evaluate_ate.py and evaluate_rpe.py): poses associated by
// timestamp, the estimate rigidly aligned to the ground truth (Horn's
// closed form, no scale), then the absolute trajectory error (ATE: distances
// between aligned positions) and the relative pose error (RPE: the error of
// the motion between two frames, which alignment does not change).
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "semrec/core/transform.h"
#include "semrec/io/pose_io.h"
#include "semrec/io/sequence_reader.h"

namespace semrec::eval {

struct TrajectoryOptions {
  /// Pairs an estimated and a ground-truth pose at most this far apart in
  /// time (s; TUM's associate.py default).
  double max_time_difference_s = 0.02;
  /// RPE between associated poses this many pairs apart (TUM's --delta with
  /// --delta_unit f).
  size_t rpe_delta_frames = 1;
  void Check() const;
};

struct TrajectoryErrors {
  /// Pairs associated by timestamp (the ATE's sample), and the poses of
  /// each input left without a partner.
  size_t associated = 0;
  size_t unmatched_estimate = 0;
  size_t unmatched_ground_truth = 0;
  /// The alignment applied to the estimate: T_gt_est.
  Transform T_ground_truth_estimate;
  /// Absolute trajectory error after alignment (m).
  double ate_rmse_m = 0.0;
  double ate_mean_m = 0.0;
  double ate_median_m = 0.0;
  double ate_max_m = 0.0;
  /// Relative pose error over rpe_delta_frames: RMSE of the translation
  /// (m) and of the rotation angle (degrees) of the pairs' motion errors.
  size_t rpe_pairs = 0;
  double rpe_translation_rmse_m = 0.0;
  double rpe_rotation_rmse_deg = 0.0;
  /// The same errors summed and divided by the ground-truth path length
  /// of the pairs: drift per metre travelled (m/m and degrees/m; 0 when the
  /// camera did not move).
  double rpe_translation_per_m = 0.0;
  double rpe_rotation_deg_per_m = 0.0;
  /// Ground-truth path length over the associated poses (m).
  double path_length_m = 0.0;
  /// Per associated pair: (estimate index, ground-truth index).
  std::vector<std::pair<size_t, size_t>> pairs;
};

/// TUM's associate.py: every pair within max_dt, closest first, each pose
/// used once. Returns (estimate index, ground-truth index) in estimate order.
std::vector<std::pair<size_t, size_t>> AssociateByTime(
    const std::vector<io::StampedPose>& estimate,
    const std::vector<io::StampedPose>& ground_truth, double max_dt_s);

/// The rigid transform T (no scale) minimising sum |T * from_i - to_i|^2
/// (Horn 1987 / Umeyama 1991 without scale). Throws InvalidArgument for fewer
/// than 3 points or different counts; collinear points give one of the
/// minimisers.
Transform AlignRigid(const std::vector<Eigen::Vector3d>& from,
                     const std::vector<Eigen::Vector3d>& to);

/// The rigid transform T_gt_est that best maps the estimated poses onto the
/// ground truth as whole poses (positions and orientations: each camera's
/// centre and the tips of its axes 1 m out, associated by time), for
/// bringing a map built from the estimate into the ground truth's frame.
/// (ATE's alignment uses the positions alone, which leaves a straight path
/// free to turn about itself.)
Transform AlignPoses(const std::vector<io::StampedPose>& estimate,
                     const std::vector<io::StampedPose>& ground_truth,
                     const TrajectoryOptions& options = {});

/// Errors of `estimate` against `ground_truth`. Throws InvalidArgument
/// (naming the counts) when fewer than 3 poses associate.
TrajectoryErrors EvaluateTrajectory(
    const std::vector<io::StampedPose>& estimate,
    const std::vector<io::StampedPose>& ground_truth,
    const TrajectoryOptions& options = {});

/// A trajectory: a TUM file ("timestamp tx ty tz qx qy qz qw"), or a
/// sequence's poses (opened with `options`, e.g. a pose correction).
std::vector<io::StampedPose> ReadTrajectory(
    const std::filesystem::path& path,
    const io::SequenceReaderOptions& options = {});

/// The summary `semrec eval traj` prints, and its --json.
std::string TrajectoryErrorsText(const TrajectoryErrors& errors);
nlohmann::json TrajectoryErrorsJson(const TrajectoryErrors& errors);

}  // namespace semrec::eval
