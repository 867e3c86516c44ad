#include "semrec/core/camera.h"

#include <gtest/gtest.h>

#include "semrec/core/error.h"

namespace semrec {
namespace {

TEST(CameraIntrinsics, ProjectInvertsBackProject) {
  const CameraIntrinsics k{640, 480, 525.0, 520.0, 319.5, 239.5};
  for (double u : {0.0, 100.5, 639.0}) {
    for (double v : {0.0, 240.0, 479.0}) {
      const Eigen::Vector3d p = k.BackProject(u, v, 2.5);
      EXPECT_DOUBLE_EQ(p.z(), 2.5);
      const Eigen::Vector2d uv = k.Project(p);
      EXPECT_NEAR(uv.x(), u, 1e-9);
      EXPECT_NEAR(uv.y(), v, 1e-9);
    }
  }
  // The principal point looks straight ahead.
  EXPECT_TRUE(
      k.BackProject(319.5, 239.5, 1.0).isApprox(Eigen::Vector3d(0, 0, 1)));
}

TEST(CameraIntrinsics, CheckRejectsBadValues) {
  EXPECT_NO_THROW((CameraIntrinsics{640, 480, 525, 525, 320, 240}.Check()));
  EXPECT_THROW((CameraIntrinsics{0, 480, 525, 525, 320, 240}.Check()),
               InvalidArgument);
  EXPECT_THROW((CameraIntrinsics{640, 480, -1, 525, 320, 240}.Check()),
               InvalidArgument);
  EXPECT_THROW((CameraIntrinsics{640, 480, 525, 525, NAN, 240}.Check()),
               InvalidArgument);
}

TEST(CameraIntrinsics, ScaledKeepsRaysThroughPixelCorners) {
  const CameraIntrinsics k{640, 480, 500.0, 500.0, 319.5, 239.5};
  const CameraIntrinsics half = k.Scaled(0.5);
  EXPECT_EQ(half.width, 320);
  EXPECT_EQ(half.height, 240);
  // The image corner (-0.5, -0.5) in full resolution is (-0.5, -0.5) at half
  // resolution too.
  const Eigen::Vector3d ray_full = k.BackProject(-0.5, -0.5, 1.0);
  const Eigen::Vector3d ray_half = half.BackProject(-0.5, -0.5, 1.0);
  EXPECT_TRUE(ray_full.isApprox(ray_half, 1e-12));
}

}  // namespace
}  // namespace semrec
