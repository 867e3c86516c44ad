// Camera poses from the RGB-D frames themselves, one frame at a time, for
// recordings that come without them. Each frame is aligned to the previous
// one by Open3D's RGB-D odometry (dense, multi-scale; hybrid photometric +
// geometric or photometric loss), and, frame-to-model, then refined by
// point-to-plane ICP against a local model: the clouds of the last keyframes
// in the world frame. (Open3D's tensor odometry and SLAM model would raycast
// a TSDF instead, but Debian's Open3D 0.16 is built without the image
// kernels they need on the CPU: FilterBilateral, RGBToGray.)
//
// Pixels the caller masks (tracked people, classes listed as dynamic) are
// left out of tracking and out of the model: a crowd walking past must not
// drag the camera with it.
//
// The world frame is the first frame's camera frame.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "semrec/core/camera.h"
#include "semrec/core/error.h"
#include "semrec/core/frame.h"
#include "semrec/core/label_map.h"
#include "semrec/core/transform.h"

namespace open3d::geometry {
class PointCloud;
class RGBDImage;
}  // namespace open3d::geometry

namespace semrec::odometry {

/// Tracking failed for too many frames in a row: the run cannot go on
/// without a wrong trajectory.
class TrackingLost : public Error {
 public:
  using Error::Error;
};

struct PoseTrackerOptions {
  enum class Method {
    /// Odometry to the previous frame, then ICP against the model (drifts
    /// less: the model holds what many frames saw).
    kFrameToModel,
    /// Odometry to the previous frame alone.
    kFrameToFrame,
    /// Odometry to the last keyframe (the reference stays put for several
    /// frames, so their errors do not add up).
    kFrameToKeyframe,
  };
  enum class Loss {
    /// Depth and intensity (Open3D's hybrid term).
    kHybrid,
    /// Intensity only (Open3D's colour term).
    kPhotometric,
  };
  Method method = Method::kFrameToKeyframe;
  Loss loss = Loss::kHybrid;
  /// Odometry works on images downsampled by this factor (depth: every
  /// n-th pixel, intensity: the n x n block's mean); 0: the largest that
  /// keeps at least 320 pixels across (2 for VGA: 2.3x faster on 7-Scenes
  /// chess at the same accuracy, docs/results.md).
  int image_downsampling = 0;
  /// Depth beyond this is left out of tracking and the model (m). Far
  /// enough for the room behind the people (Bonn crowd's walls are 3.3 m
  /// and more away).
  double max_depth_m = 6.0;
  /// Odometry: pixels whose depths differ by more than this do not
  /// correspond (m).
  double depth_diff_m = 0.07;
  /// Odometry iterations per pyramid level, coarse to fine.
  std::vector<int> iterations = {20, 10, 5};
  /// The clouds ICP aligns and the model are downsampled to this voxel (m).
  double cloud_voxel_m = 0.02;
  /// ICP pairs at most this far apart (m).
  double icp_max_distance_m = 0.05;
  /// A frame this far from the last keyframe (m or degrees) becomes one
  /// and joins the model.
  double keyframe_step_m = 0.1;
  double keyframe_step_deg = 10.0;
  /// The model holds the clouds of this many latest keyframes.
  size_t model_keyframes = 30;
  /// A frame is lost when its fitness (the share of its cloud with a model
  /// or previous-frame point within icp_max_distance_m) is below this, or
  /// when it moved more than the limits below since the last tracked
  /// frame: it keeps the last pose and joins nothing.
  double min_fitness = 0.3;
  double max_step_m = 0.3;
  double max_step_deg = 30.0;
  /// This many lost frames in a row stop tracking (TrackingLost).
  size_t max_lost_frames = 10;
  void Check() const;
};

const char* MethodName(PoseTrackerOptions::Method method);
PoseTrackerOptions::Method ParseMethod(const std::string& text);
const char* LossName(PoseTrackerOptions::Loss loss);

struct PoseTrackResult {
  /// The frame's estimated camera-to-world pose.
  Transform T_world_camera;
  /// False when the frame was lost (it has the last tracked pose).
  bool tracked = true;
  /// Fitness and inlier RMSE (m) of the frame's cloud against the model
  /// (frame-to-model) or the previous frame; 1 and 0 for the first frame.
  double fitness = 1.0;
  double inlier_rmse_m = 0.0;
  /// Pixels left out by the mask.
  size_t masked_pixels = 0;
  bool keyframe = false;
  /// Why a frame was lost (empty when tracked).
  std::string lost_reason;
};

class PoseTracker {
 public:
  PoseTracker(const PoseTrackerOptions& options,
              const CameraIntrinsics& intrinsics);
  ~PoseTracker();
  PoseTracker(const PoseTracker&) = delete;
  PoseTracker& operator=(const PoseTracker&) = delete;

  /// Estimates `frame`'s pose (its T_world_camera is not read). `masked`:
  /// pixels to leave out (non-zero), e.g. tracked people; null for none.
  /// Throws TrackingLost after max_lost_frames lost frames in a row, and
  /// InvalidArgument for a frame of another size than the intrinsics.
  PoseTrackResult Track(const Frame& frame, const LabelMap* masked = nullptr);

  size_t frames() const { return frames_; }
  size_t lost_frames() const { return lost_total_; }
  size_t keyframes() const { return keyframes_; }

 private:
  struct State;
  // A frame as tracking uses it: intensity + depth (downsampled, masked)
  // and its cloud in the camera frame.
  struct Prepared {
    std::shared_ptr<open3d::geometry::RGBDImage> rgbd;
    std::shared_ptr<open3d::geometry::PointCloud> cloud;
  };
  struct Alignment {
    Transform T_reference_current;
    double fitness = 0.0, inlier_rmse_m = 0.0;
  };
  Prepared Prepare(const Frame& frame, const LabelMap* masked,
                   size_t* masked_pixels) const;
  std::optional<Alignment> Align(const Prepared& current,
                                 const Prepared& reference,
                                 const Transform& T_reference_guess) const;
  // Why a pose cannot be right (empty: plausible).
  std::string Implausible(const Alignment& a,
                          const Transform& T_world_camera) const;
  Alignment Refine(const Prepared& current, Transform* T_world_camera) const;
  void AddToModel(const Prepared& current, const Transform& T_world_camera);
  PoseTrackResult Lose(const Frame& frame, const std::string& why,
                       PoseTrackResult result);

  PoseTrackerOptions options_;
  CameraIntrinsics intrinsics_;
  std::unique_ptr<State> state_;
  size_t frames_ = 0, lost_in_a_row_ = 0, lost_total_ = 0, keyframes_ = 0;
};

}  // namespace semrec::odometry
