#include "semrec/core/transform.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <Eigen/SVD>

#include "semrec/core/error.h"

namespace semrec {

Transform::Transform(const Eigen::Matrix3d& rotation,
                     const Eigen::Vector3d& translation)
    : rotation_(rotation), translation_(translation) {}

Transform Transform::FromMatrix(const Eigen::Matrix4d& matrix,
                                const std::string& what, double tolerance) {
  if (!matrix.allFinite()) {
    throw InvalidArgument(what + ": matrix has non-finite entries");
  }
  const Eigen::RowVector4d last = matrix.row(3);
  if ((last - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() >
      tolerance) {
    throw InvalidArgument(
        fmt::format("{}: last row must be 0 0 0 1, got {} {} {} {}", what,
                    last(0), last(1), last(2), last(3)));
  }
  const Eigen::Matrix3d r = matrix.topLeftCorner<3, 3>();
  const double orthonormality_error =
      (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (orthonormality_error > tolerance) {
    throw InvalidArgument(
        fmt::format("{}: rotation block is not orthonormal (max |R^T R - I| = "
                    "{:.3g} > {:.1g}); the pose is "
                    "not rigid (scaled or sheared?)",
                    what, orthonormality_error, tolerance));
  }
  if (r.determinant() < 0.0) {
    throw InvalidArgument(
        what +
        ": rotation block has determinant -1 (a reflection, not a pose)");
  }
  // Remove the rounding noise of text files so that products of many poses stay
  // rigid.
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(
      r, Eigen::ComputeFullU | Eigen::ComputeFullV);
  return Transform(svd.matrixU() * svd.matrixV().transpose(),
                   matrix.topRightCorner<3, 1>());
}

Transform Transform::FromQuaternion(const Eigen::Quaterniond& q,
                                    const Eigen::Vector3d& t) {
  const double norm = q.norm();
  if (!std::isfinite(norm) || norm < 1e-12 || !t.allFinite()) {
    throw InvalidArgument(
        "pose: quaternion or translation is zero or non-finite");
  }
  return Transform(q.normalized().toRotationMatrix(), t);
}

Eigen::Matrix4d Transform::Matrix() const {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = rotation_;
  m.topRightCorner<3, 1>() = translation_;
  return m;
}

Transform Transform::Inverse() const {
  const Eigen::Matrix3d r_inv = rotation_.transpose();
  return Transform(r_inv, -(r_inv * translation_));
}

Transform Transform::operator*(const Transform& other) const {
  return Transform(rotation_ * other.rotation_,
                   rotation_ * other.translation_ + translation_);
}

double Transform::AngleRad() const {
  const double c = std::clamp((rotation_.trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c);
}

double Transform::AngleDeg() const { return AngleRad() * 180.0 / M_PI; }

Transform Transform::Interpolate(const Transform& a, const Transform& b,
                                 double t) {
  const Eigen::Quaterniond q = a.Quaternion().slerp(t, b.Quaternion());
  return Transform(q.toRotationMatrix(),
                   (1.0 - t) * a.translation_ + t * b.translation_);
}

bool Transform::IsApprox(const Transform& other, double tolerance) const {
  return (rotation_ - other.rotation_).cwiseAbs().maxCoeff() <= tolerance &&
         (translation_ - other.translation_).cwiseAbs().maxCoeff() <= tolerance;
}

Transform LookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                 const Eigen::Vector3d& up_world) {
  const Eigen::Vector3d forward = target - eye;
  CheckArgument(forward.norm() > 1e-12, "LookAt: eye and target coincide");
  const Eigen::Vector3d z = forward.normalized();
  const Eigen::Vector3d x = z.cross(up_world);
  CheckArgument(x.norm() > 1e-9,
                "LookAt: view direction is parallel to the up vector");
  Eigen::Matrix3d R;
  R.col(0) = x.normalized();
  R.col(2) = z;
  R.col(1) = z.cross(R.col(0));
  return Transform(R, eye);
}

}  // namespace semrec
