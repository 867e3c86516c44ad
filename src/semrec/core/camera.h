// Pinhole camera intrinsics.
#pragma once

#include <string>

#include <Eigen/Core>

namespace semrec {

/// Pinhole intrinsics of a width x height image. Pixel centres are at integer
/// coordinates: pixel (u, v) with depth z back-projects to ((u - cx) z / fx, (v
/// - cy) z / fy, z) in the camera frame (x right, y down, z forward), the
/// convention of Open3D, TUM and 7-Scenes.
struct CameraIntrinsics {
  int width = 0;
  int height = 0;
  double fx = 0.0;
  double fy = 0.0;
  double cx = 0.0;
  double cy = 0.0;

  /// Throws InvalidArgument unless sizes and focal lengths are positive and
  /// finite.
  void Check() const;

  /// The 3x3 calibration matrix K.
  Eigen::Matrix3d K() const;

  /// Point in the camera frame for pixel (u, v) at depth z (metres).
  Eigen::Vector3d BackProject(double u, double v, double z) const {
    return {(u - cx) * z / fx, (v - cy) * z / fy, z};
  }

  /// Pixel coordinates (u, v) of a camera-frame point with z > 0.
  Eigen::Vector2d Project(const Eigen::Vector3d& p_camera) const {
    return {fx * p_camera.x() / p_camera.z() + cx,
            fy * p_camera.y() / p_camera.z() + cy};
  }

  /// Same intrinsics for an image resized by `scale` (e.g. 0.5 for half
  /// resolution).
  CameraIntrinsics Scaled(double scale) const;

  std::string ToString() const;

  bool operator==(const CameraIntrinsics&) const = default;
};

}  // namespace semrec
