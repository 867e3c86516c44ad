// Which way is up: real recordings come with arbitrary world frames (7-Scenes'
// is the first camera's: y down, tilted). The scene is written Z-up with the
// floor at z = 0, so viewers, simulators and queries ("what is on the floor")
// see it upright.
//
// Estimate: the cameras' up (perpendicular to their x axes when those turn
// enough, else their image-up: people hold RGB-D cameras with little roll)
// picks the horizontal planes among the planes RANSAC finds in the fused
// points (normal within max_tilt_deg of it, not looked up at); the normal of
// the largest such plane refined by least squares is "up". The floor is the
// lowest horizontal plane holding at least min_floor_share of the horizontal
// points (or the points of a class named "floor" when the scene has them).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "semrec/core/transform.h"
#include "semrec/fuse/voxel.h"

namespace semrec::fuse {

struct GravityOptions {
  enum class Mode {
    /// Estimate from the cameras and the scene.
    kAuto,
    /// Keep the world frame as it is.
    kNone,
    /// `up` is given (world frame); the floor height is still estimated.
    kGiven,
  };
  Mode mode = Mode::kAuto;
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  /// Planes whose normal is farther than this from the cameras' up vector are
  /// not floors, tables or ceilings. Generous, because a camera that barely
  /// turns leaves its pitch in that vector (looking down at a table: 29
  /// degrees on 7-Scenes chess, 48 on the six-objects orbit).
  double max_tilt_deg = 60.0;
  /// ... and planes the cameras look up at by more than this on average are
  /// walls seen from a camera pitched down, not floors.
  double max_look_up_deg = 20.0;
  /// RANSAC inlier distance.
  double plane_tolerance_m = 0.03;
  /// A horizontal plane counts as the floor candidate from this share of the
  /// largest horizontal plane's points.
  double min_floor_share = 0.2;
  /// An already upright frame (estimated up within this angle of +Z and floor
  /// within snap_height_m of z = 0) is kept exactly as it is.
  double snap_angle_deg = 2.0;
  double snap_height_m = 0.02;
  uint64_t seed = 1;

  void Check() const;
};

/// Parses "auto", "none" or "x,y,z" (the world's up direction). Throws
/// InvalidArgument naming the flag otherwise.
GravityOptions ParseGravity(const std::string& text);

struct GravityEstimate {
  /// Maps world coordinates to the upright frame (Z up, floor at z = 0).
  Transform T_upright_world;
  /// Up (world frame) and the floor's height along it.
  Eigen::Vector3d up_world = Eigen::Vector3d::UnitZ();
  double floor_height_m = 0.0;
  /// How it was decided: "none", "given", "floor class", "planes",
  /// "cameras" (no horizontal plane: the cameras' up and the lowest points),
  /// "already upright".
  std::string method = "none";
  /// Points on the floor plane used (0 when none).
  size_t floor_points = 0;
};

/// `clouds`: the scene's points (world frame), one cloud per object;
/// `is_floor`: parallel flags for clouds of a "floor" class (may be empty).
/// `T_world_cameras`: the camera poses.
GravityEstimate EstimateGravity(const std::vector<const Cloud*>& clouds,
                                const std::vector<bool>& is_floor,
                                const std::vector<Transform>& T_world_cameras,
                                const GravityOptions& options);

}  // namespace semrec::fuse
