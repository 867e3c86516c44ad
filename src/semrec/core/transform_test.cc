#include "semrec/core/transform.h"

#include <gtest/gtest.h>

#include "semrec/core/error.h"

namespace semrec {
namespace {

Transform Example() {
  return Transform(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized())
                       .toRotationMatrix(),
                   Eigen::Vector3d(0.5, -1.0, 2.0));
}

TEST(Transform, ComposeAndInverse) {
  const Transform T_world_camera = Example();
  const Eigen::Vector3d p_camera(0.1, 0.2, 1.5);
  const Eigen::Vector3d p_world = T_world_camera * p_camera;
  EXPECT_TRUE((T_world_camera.Inverse() * p_world).isApprox(p_camera, 1e-12));
  EXPECT_TRUE(
      (T_world_camera * T_world_camera.Inverse()).IsApprox(Transform(), 1e-12));
  // Matrix form agrees with the point form.
  const Eigen::Vector4d h = T_world_camera.Matrix() * p_camera.homogeneous();
  EXPECT_TRUE(h.head<3>().isApprox(p_world, 1e-12));
}

TEST(Transform, FromMatrixRoundTrip) {
  const Transform t = Example();
  EXPECT_TRUE(Transform::FromMatrix(t.Matrix()).IsApprox(t, 1e-12));
}

TEST(Transform, FromMatrixRejectsNonRigid) {
  Eigen::Matrix4d scaled = Example().Matrix();
  scaled.topLeftCorner<3, 3>() *= 1.1;
  EXPECT_THROW(Transform::FromMatrix(scaled), InvalidArgument);

  Eigen::Matrix4d sheared = Eigen::Matrix4d::Identity();
  sheared(0, 1) = 0.2;
  EXPECT_THROW(Transform::FromMatrix(sheared), InvalidArgument);

  Eigen::Matrix4d reflection = Eigen::Matrix4d::Identity();
  reflection(2, 2) = -1.0;
  EXPECT_THROW(Transform::FromMatrix(reflection), InvalidArgument);

  Eigen::Matrix4d bad_row = Eigen::Matrix4d::Identity();
  bad_row(3, 0) = 1.0;
  EXPECT_THROW(Transform::FromMatrix(bad_row), InvalidArgument);

  Eigen::Matrix4d nan = Eigen::Matrix4d::Identity();
  nan(1, 3) = std::numeric_limits<double>::quiet_NaN();
  try {
    Transform::FromMatrix(nan, "frame 7 pose");
    FAIL() << "expected an exception";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("frame 7 pose"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("non-finite"), std::string::npos);
  }
}

TEST(Transform, SmallRoundingIsAcceptedAndCleaned) {
  Eigen::Matrix4d m = Example().Matrix();
  m(0, 0) += 1e-5;  // typical of poses printed with 6 digits
  const Transform t = Transform::FromMatrix(m);
  const Eigen::Matrix3d r = t.rotation();
  EXPECT_LT((r.transpose() * r - Eigen::Matrix3d::Identity()).norm(), 1e-12);
}

TEST(Transform, InterpolateEndsAndMiddle) {
  const Transform a;
  const Transform b(
      Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitZ()).toRotationMatrix(),
      Eigen::Vector3d(2, 0, 0));
  EXPECT_TRUE(Transform::Interpolate(a, b, 0.0).IsApprox(a, 1e-12));
  EXPECT_TRUE(Transform::Interpolate(a, b, 1.0).IsApprox(b, 1e-12));
  const Transform mid = Transform::Interpolate(a, b, 0.5);
  EXPECT_NEAR(mid.AngleRad(), 0.5, 1e-12);
  EXPECT_TRUE(mid.translation().isApprox(Eigen::Vector3d(1, 0, 0)));
}

TEST(Transform, QuaternionIsNormalised) {
  const Transform t = Transform::FromQuaternion(
      Eigen::Quaterniond(2.0, 0.0, 0.0, 0.0), Eigen::Vector3d(1, 2, 3));
  EXPECT_TRUE(t.rotation().isApprox(Eigen::Matrix3d::Identity()));
  EXPECT_THROW(Transform::FromQuaternion(Eigen::Quaterniond(0, 0, 0, 0),
                                         Eigen::Vector3d::Zero()),
               InvalidArgument);
}

TEST(Transform, LookAtConvention) {
  // Looking along world +x with z up: camera x (right) is world -y, camera y
  // (down) is world -z.
  const Transform T_world_camera = LookAt({1, 2, 3}, {5, 2, 3});
  EXPECT_TRUE((T_world_camera.rotation() * Eigen::Vector3d::UnitX())
                  .isApprox(-Eigen::Vector3d::UnitY()));
  EXPECT_TRUE((T_world_camera.rotation() * Eigen::Vector3d::UnitY())
                  .isApprox(-Eigen::Vector3d::UnitZ()));
  EXPECT_TRUE((T_world_camera.Inverse() * Eigen::Vector3d(5, 2, 3))
                  .isApprox(Eigen::Vector3d(0, 0, 4)));
  EXPECT_NEAR(T_world_camera.rotation().determinant(), 1.0, 1e-12);
  EXPECT_THROW(LookAt({0, 0, 0}, {0, 0, 1}), InvalidArgument);
}

}  // namespace
}  // namespace semrec
