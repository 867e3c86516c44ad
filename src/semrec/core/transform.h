// Rigid transforms. Name variables after the frames they connect:
// `T_world_camera` maps points from the camera frame into the world frame
// (p_world = T_world_camera * p_camera), so frames chain visibly: T_a_c = T_a_b
// * T_b_c.
#pragma once

#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace semrec {

/// A rigid transform (rotation + translation) in double precision.
class Transform {
 public:
  /// Identity.
  Transform() = default;
  Transform(const Eigen::Matrix3d& rotation,
            const Eigen::Vector3d& translation);

  /// From a 4x4 homogeneous matrix. Throws InvalidArgument (with `what` in the
  /// message) when the matrix has non-finite entries, a last row other than (0
  /// 0 0 1), or a rotation block that is not orthonormal with determinant +1
  /// within `tolerance`. The rotation is re-orthonormalised.
  static Transform FromMatrix(const Eigen::Matrix4d& matrix,
                              const std::string& what = "pose",
                              double tolerance = 1e-3);

  /// From a unit quaternion (any norm is accepted and normalised) and a
  /// translation.
  static Transform FromQuaternion(const Eigen::Quaterniond& q,
                                  const Eigen::Vector3d& t);

  const Eigen::Matrix3d& rotation() const { return rotation_; }
  const Eigen::Vector3d& translation() const { return translation_; }
  Eigen::Matrix4d Matrix() const;
  Eigen::Quaterniond Quaternion() const {
    return Eigen::Quaterniond(rotation_);
  }

  Transform Inverse() const;
  Transform operator*(const Transform& other) const;
  Eigen::Vector3d operator*(const Eigen::Vector3d& p) const {
    return rotation_ * p + translation_;
  }

  /// Rotation angle (radians) of this transform.
  double AngleRad() const;
  /// ... in degrees.
  double AngleDeg() const;

  /// Linear interpolation of translation and slerp of rotation; t in [0, 1].
  static Transform Interpolate(const Transform& a, const Transform& b,
                               double t);

  bool IsApprox(const Transform& other, double tolerance = 1e-9) const;

 private:
  Eigen::Matrix3d rotation_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation_ = Eigen::Vector3d::Zero();
};

/// T_world_camera of a camera at `eye` looking at `target`, with the camera
/// convention x right, y down, z forward and `up_world` pointing up in the
/// image. Throws InvalidArgument when eye and target coincide or the view
/// direction is parallel to up_world.
Transform LookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                 const Eigen::Vector3d& up_world = Eigen::Vector3d::UnitZ());

}  // namespace semrec
