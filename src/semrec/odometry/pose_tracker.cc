#include "semrec/odometry/pose_tracker.h"

#include <cmath>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <tuple>
#include <vector>

#include <fmt/format.h>
#include <open3d/camera/PinholeCameraIntrinsic.h>
#include <open3d/geometry/Image.h>
#include <open3d/geometry/KDTreeSearchParam.h>
#include <open3d/geometry/PointCloud.h>
#include <open3d/geometry/RGBDImage.h>
#include <open3d/pipelines/odometry/Odometry.h>
#include <open3d/pipelines/registration/Registration.h>
#include <open3d/pipelines/registration/TransformationEstimation.h>
#include <spdlog/spdlog.h>

#include "semrec/core/enum_names.h"

namespace semrec::odometry {
namespace {

namespace o3g = open3d::geometry;
namespace o3o = open3d::pipelines::odometry;
namespace o3r = open3d::pipelines::registration;

// Every n-th pixel (both ways) goes into the ICP cloud before downsampling.
constexpr int kCloudPixelStride = 2;

// The masked depth's points in the camera frame, downsampled.
std::shared_ptr<o3g::PointCloud> CameraCloud(const o3g::Image& depth,
                                             const CameraIntrinsics& k,
                                             double voxel_m) {
  auto cloud = std::make_shared<o3g::PointCloud>();
  const auto* d = depth.PointerAs<float>();
  for (int v = 0; v < depth.height_; v += kCloudPixelStride) {
    for (int u = 0; u < depth.width_; u += kCloudPixelStride) {
      const double z = d[static_cast<size_t>(v) * depth.width_ + u];
      if (z <= 0.0) continue;
      cloud->points_.push_back(k.BackProject(u, v, z));
    }
  }
  return cloud->VoxelDownSample(voxel_m);
}

}  // namespace

const char* MethodName(PoseTrackerOptions::Method method) {
  switch (method) {
    case PoseTrackerOptions::Method::kFrameToModel:
      return "frame-to-model";
    case PoseTrackerOptions::Method::kFrameToFrame:
      return "frame-to-frame";
    case PoseTrackerOptions::Method::kFrameToKeyframe:
      return "frame-to-keyframe";
  }
  return "?";
}

const char* LossName(PoseTrackerOptions::Loss loss) {
  return loss == PoseTrackerOptions::Loss::kHybrid ? "hybrid" : "photometric";
}

PoseTrackerOptions::Method ParseMethod(const std::string& text) {
  return ParseEnumName(text,
                       {PoseTrackerOptions::Method::kFrameToModel,
                        PoseTrackerOptions::Method::kFrameToFrame,
                        PoseTrackerOptions::Method::kFrameToKeyframe},
                       MethodName, "odometry method");
}

void PoseTrackerOptions::Check() const {
  CheckArgument(image_downsampling >= 0 && image_downsampling <= 8,
                "odometry: image_downsampling must be 0 (auto) to 8");
  CheckArgument(max_depth_m > 0.0, "odometry: max_depth_m must be > 0");
  CheckArgument(depth_diff_m > 0.0, "odometry: depth_diff_m must be > 0");
  CheckArgument(!iterations.empty(),
                "odometry: give at least one pyramid level's iterations");
  for (const int n : iterations) {
    CheckArgument(n >= 1, "odometry: iterations per level must be >= 1");
  }
  CheckArgument(cloud_voxel_m > 0.0 && std::isfinite(cloud_voxel_m),
                "odometry: cloud_voxel_m must be > 0");
  CheckArgument(icp_max_distance_m > 0.0,
                "odometry: icp_max_distance_m must be > 0");
  CheckArgument(keyframe_step_m > 0.0 && keyframe_step_deg > 0.0,
                "odometry: the keyframe steps must be > 0");
  CheckArgument(model_keyframes >= 1, "odometry: model_keyframes must be >= 1");
  CheckArgument(min_fitness >= 0.0 && min_fitness <= 1.0,
                "odometry: min_fitness must be in [0, 1]");
  CheckArgument(max_step_m > 0.0 && max_step_deg > 0.0,
                "odometry: the step limits must be > 0");
  CheckArgument(max_lost_frames >= 1, "odometry: max_lost_frames must be >= 1");
}

struct PoseTracker::State {
  // The intrinsics of the images odometry works on (downsampled).
  open3d::camera::PinholeCameraIntrinsic intrinsic;
  CameraIntrinsics scaled;
  int factor = 1;
  // The last tracked frame and the motion that led to it (the next frame's
  // first guess).
  Prepared previous;
  Transform T_world_last, T_last_step;
  // The last keyframe.
  Prepared keyframe;
  Transform T_world_keyframe;
  // Frame-to-model: the latest keyframes' clouds (world frame, with
  // normals), merged and downsampled when a keyframe joins.
  std::deque<std::shared_ptr<o3g::PointCloud>> keyframe_clouds;
  std::shared_ptr<o3g::PointCloud> model;
};

PoseTracker::PoseTracker(const PoseTrackerOptions& options,
                         const CameraIntrinsics& intrinsics)
    : options_((options.Check(), options)),
      intrinsics_((intrinsics.Check(), intrinsics)),
      state_(std::make_unique<State>()) {
  int f = options_.image_downsampling;
  if (f == 0) {
    f = 1;
    while (intrinsics.width / (2 * f) >= 320) f *= 2;
  }
  state_->factor = f;
  CameraIntrinsics& k = state_->scaled;
  k = {intrinsics.width / f, intrinsics.height / f, intrinsics.fx / f,
       intrinsics.fy / f,    intrinsics.cx / f,     intrinsics.cy / f};
  state_->intrinsic.SetIntrinsics(k.width, k.height, k.fx, k.fy, k.cx, k.cy);
}

PoseTracker::~PoseTracker() = default;

PoseTracker::Prepared PoseTracker::Prepare(const Frame& frame,
                                           const LabelMap* masked,
                                           size_t* masked_pixels) const {
  const int f = state_->factor;
  const CameraIntrinsics& k = state_->scaled;
  // Depth: every f-th pixel (averaging would mix depths across edges);
  // intensity: the f x f block's mean.
  o3g::Image depth, intensity;
  depth.Prepare(k.width, k.height, 1, 4);
  intensity.Prepare(k.width, k.height, 1, 4);
  auto* d = depth.PointerAs<float>();
  auto* gray = intensity.PointerAs<float>();
  const float max_depth = static_cast<float>(options_.max_depth_m);
  // The mask on the downsampled grid: a cell any of whose pixels is masked.
  std::vector<uint8_t> cell_masked;
  if (masked != nullptr) {
    cell_masked.assign(static_cast<size_t>(k.width) * k.height, 0);
    for (int y = 0; y < masked->height(); ++y) {
      for (int x = 0; x < masked->width(); ++x) {
        if ((*masked)(x, y) == 0) continue;
        ++*masked_pixels;
        if (x / f < k.width && y / f < k.height) {
          cell_masked[static_cast<size_t>(y / f) * k.width + x / f] = 1;
        }
      }
    }
  }
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const size_t out = static_cast<size_t>(v) * k.width + u;
      const int x = u * f, y = v * f;
      float z = frame.depth(x, y);
      if (!cell_masked.empty() && cell_masked[out] != 0) z = 0.0f;
      d[out] = std::isfinite(z) && z > 0.0f && z < max_depth ? z : 0.0f;
      float sum = 0.0f;
      for (int dy = 0; dy < f; ++dy) {
        for (int dx = 0; dx < f; ++dx) {
          // Open3D's intensity weights (Image::CreateFloatImage).
          sum += 0.2990f * frame.color(x + dx, y + dy, 0) +
                 0.5870f * frame.color(x + dx, y + dy, 1) +
                 0.1140f * frame.color(x + dx, y + dy, 2);
        }
      }
      gray[out] = sum / (255.0f * static_cast<float>(f * f));
    }
  }
  Prepared out;
  out.rgbd = std::make_shared<o3g::RGBDImage>(intensity, depth);
  out.cloud = CameraCloud(depth, k, options_.cloud_voxel_m);
  return out;
}

std::optional<PoseTracker::Alignment> PoseTracker::Align(
    const Prepared& current, const Prepared& reference,
    const Transform& T_reference_guess) const {
  const o3o::OdometryOption option(options_.iterations, options_.depth_diff_m,
                                   0.0, options_.max_depth_m);
  const auto jacobian =
      options_.loss == PoseTrackerOptions::Loss::kHybrid
          ? std::shared_ptr<o3o::RGBDOdometryJacobian>(
                std::make_shared<o3o::RGBDOdometryJacobianFromHybridTerm>())
          : std::make_shared<o3o::RGBDOdometryJacobianFromColorTerm>();
  const auto [ok, T_reference_current, information] = o3o::ComputeRGBDOdometry(
      *current.rgbd, *reference.rgbd, state_->intrinsic,
      T_reference_guess.Matrix(), *jacobian, option);
  if (!ok || current.cloud->points_.empty()) return std::nullopt;
  Alignment out;
  out.T_reference_current =
      Transform::FromMatrix(T_reference_current, "odometry step", 1e-2);
  const o3r::RegistrationResult check = o3r::EvaluateRegistration(
      *current.cloud, *reference.cloud, options_.icp_max_distance_m,
      out.T_reference_current.Matrix());
  out.fitness = check.fitness_;
  out.inlier_rmse_m = check.inlier_rmse_;
  return out;
}

std::string PoseTracker::Implausible(const Alignment& a,
                                     const Transform& T_world_camera) const {
  const Transform moved = state_->T_world_last.Inverse() * T_world_camera;
  if (a.fitness < options_.min_fitness) {
    return fmt::format("fitness {:.2f} below {:.2f}", a.fitness,
                       options_.min_fitness);
  }
  if (moved.translation().norm() > options_.max_step_m ||
      moved.AngleDeg() > options_.max_step_deg) {
    return fmt::format(
        "a jump of {:.2f} m / {:.1f} degrees from the last tracked frame",
        moved.translation().norm(), moved.AngleDeg());
  }
  return "";
}

// Frame-to-model: point-to-plane ICP of the frame's cloud against the model
// from the odometry's pose.
PoseTracker::Alignment PoseTracker::Refine(const Prepared& current,
                                           Transform* T_world_camera) const {
  const o3r::RegistrationResult icp = o3r::RegistrationICP(
      *current.cloud, *state_->model, options_.icp_max_distance_m,
      T_world_camera->Matrix(), o3r::TransformationEstimationPointToPlane(),
      o3r::ICPConvergenceCriteria(1e-6, 1e-6, 30));
  *T_world_camera =
      Transform::FromMatrix(icp.transformation_, "ICP pose", 1e-2);
  Alignment out;
  out.fitness = icp.fitness_;
  out.inlier_rmse_m = icp.inlier_rmse_;
  return out;
}

void PoseTracker::AddToModel(const Prepared& current,
                             const Transform& T_world_camera) {
  State& s = *state_;
  if (current.cloud->points_.empty()) return;
  auto world = std::make_shared<o3g::PointCloud>(*current.cloud);
  world->EstimateNormals(
      o3g::KDTreeSearchParamHybrid(3.0 * options_.cloud_voxel_m, 30));
  world->OrientNormalsTowardsCameraLocation(Eigen::Vector3d::Zero());
  world->Transform(T_world_camera.Matrix());
  s.keyframe_clouds.push_back(world);
  if (s.keyframe_clouds.size() > options_.model_keyframes) {
    s.keyframe_clouds.pop_front();
  }
  auto merged = std::make_shared<o3g::PointCloud>();
  for (const auto& c : s.keyframe_clouds) *merged += *c;
  s.model = merged->VoxelDownSample(options_.cloud_voxel_m);
}

PoseTrackResult PoseTracker::Track(const Frame& frame, const LabelMap* masked) {
  CheckArgument(
      frame.depth.SameSize(intrinsics_.width, intrinsics_.height) &&
          frame.color.SameSize(frame.depth),
      fmt::format("odometry: frame {} is {}x{}, the camera {}x{}", frame.index,
                  frame.depth.width(), frame.depth.height(), intrinsics_.width,
                  intrinsics_.height));
  CheckArgument(masked == nullptr || masked->SameSize(frame.depth),
                "odometry: the mask differs in size from the frame");
  State& s = *state_;
  PoseTrackResult result;
  const Prepared current = Prepare(frame, masked, &result.masked_pixels);
  const size_t index = frames_++;
  bool force_keyframe = index == 0;
  if (index > 0) {
    using Method = PoseTrackerOptions::Method;
    // From the last motion; against the keyframe first where asked, then
    // against the previous frame (a new keyframe follows).
    const Transform guess_world = s.T_world_last * s.T_last_step;
    std::optional<Alignment> a;
    Transform T_world_camera;
    if (options_.method == Method::kFrameToKeyframe) {
      a = Align(current, s.keyframe,
                s.T_world_keyframe.Inverse() * guess_world);
      if (a) T_world_camera = s.T_world_keyframe * a->T_reference_current;
      force_keyframe = !a || !Implausible(*a, T_world_camera).empty();
    }
    if (options_.method != Method::kFrameToKeyframe || force_keyframe) {
      a = Align(current, s.previous, s.T_last_step);
      if (a) T_world_camera = s.T_world_last * a->T_reference_current;
      // A wrong last motion is a bad first guess: try again from rest
      // (unless that was the guess).
      if ((!a || !Implausible(*a, T_world_camera).empty()) &&
          !s.T_last_step.IsApprox(Transform())) {
        a = Align(current, s.previous, Transform());
        if (a) T_world_camera = s.T_world_last * a->T_reference_current;
      }
    }
    if (options_.method == Method::kFrameToModel && s.model &&
        !current.cloud->points_.empty()) {
      if (!a) T_world_camera = guess_world;
      a = Refine(current, &T_world_camera);
    }
    std::string lost;
    if (!a) {
      lost = "the odometry found too few correspondences";
    } else {
      lost = Implausible(*a, T_world_camera);
      result.fitness = a->fitness;
      result.inlier_rmse_m = a->inlier_rmse_m;
    }
    spdlog::debug(
        "odometry frame {}: fitness {:.3f}, inlier RMSE {:.4f} m, moved {:.4f} "
        "m{}{}",
        frame.index, result.fitness, result.inlier_rmse_m,
        (s.T_world_last.Inverse() * T_world_camera).translation().norm(),
        force_keyframe && index > 0 ? ", against the previous frame" : "",
        lost.empty() ? "" : ", lost: " + lost);
    if (!lost.empty()) return Lose(frame, lost, result);
    s.T_last_step = s.T_world_last.Inverse() * T_world_camera;
    s.T_world_last = T_world_camera;
  }
  lost_in_a_row_ = 0;
  s.previous = current;
  result.T_world_camera = s.T_world_last;
  const Transform from_keyframe = s.T_world_keyframe.Inverse() * s.T_world_last;
  result.keyframe =
      force_keyframe ||
      from_keyframe.translation().norm() > options_.keyframe_step_m ||
      from_keyframe.AngleDeg() > options_.keyframe_step_deg;
  if (result.keyframe) {
    ++keyframes_;
    s.T_world_keyframe = s.T_world_last;
    s.keyframe = current;
    if (options_.method == PoseTrackerOptions::Method::kFrameToModel) {
      AddToModel(current, s.T_world_last);
    }
  }
  return result;
}

PoseTrackResult PoseTracker::Lose(const Frame& frame, const std::string& why,
                                  PoseTrackResult result) {
  result.tracked = false;
  result.lost_reason = why;
  // The next frame starts from rest, not from a motion that led astray.
  state_->T_last_step = Transform();
  result.T_world_camera = state_->T_world_last;
  ++lost_total_;
  if (++lost_in_a_row_ >= options_.max_lost_frames) {
    throw TrackingLost(fmt::format(
        "camera tracking lost at frame {} ({}): {} frames in a row could not "
        "be aligned (last: {}); the trajectory after frame {} would be wrong",
        frame.index, frame.depth_path.string(), lost_in_a_row_, why,
        frame.index + 1 - lost_in_a_row_));
  }
  return result;
}

}  // namespace semrec::odometry
