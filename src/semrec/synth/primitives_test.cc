#include "semrec/synth/primitives.h"

#include <random>

#include <gtest/gtest.h>

namespace semrec::synth {
namespace {

std::vector<Primitive> Shapes() {
  return {
      Box{{0.1, -0.2, 0.3},
          {0.4, 0.2, 0.3},
          Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, 1, 0).normalized())
              .toRotationMatrix()},
      Cylinder{{0, 0, 0}, {0.2, 0.1, 0.8}, 0.25},
      Capsule{{-0.3, 0, 0}, {0.3, 0.2, 0.1}, 0.15},
      Sphere{{0.05, 0.1, -0.1}, 0.4},
  };
}

TEST(Primitives, KnownIntersections) {
  const Box box{{0, 0, 0}, {1, 2, 3}, Eigen::Matrix3d::Identity()};
  auto hit = Intersect(box, {-5, 0, 0}, {1, 0, 0}, 0, 100);
  ASSERT_TRUE(hit);
  EXPECT_DOUBLE_EQ(hit->t, 4.0);
  EXPECT_TRUE(hit->normal.isApprox(Eigen::Vector3d(-1, 0, 0)));
  // From inside, the exit face (how the room is seen).
  hit = Intersect(box, {0, 0, 0}, {0, 0, 2}, 0, 100);
  ASSERT_TRUE(hit);
  EXPECT_DOUBLE_EQ(hit->t, 1.5);
  const Cylinder cyl{{0, 0, 0}, {0, 0, 2}, 0.5};
  hit = Intersect(cyl, {3, 0, 1}, {-1, 0, 0}, 0, 100);
  ASSERT_TRUE(hit);
  EXPECT_DOUBLE_EQ(hit->t, 2.5);
  hit = Intersect(cyl, {0.1, 0, 5}, {0, 0, -1}, 0, 100);  // top cap
  ASSERT_TRUE(hit);
  EXPECT_DOUBLE_EQ(hit->t, 3.0);
  EXPECT_TRUE(hit->normal.isApprox(Eigen::Vector3d::UnitZ()));
  EXPECT_FALSE(
      Intersect(cyl, {3, 0, 3}, {-1, 0, 0}, 0, 100));  // above the cylinder
  EXPECT_FALSE(Intersect(Sphere{{0, 0, 0}, 1}, {0, 0, 5}, {0, 0, -1}, 0,
                         3.9));  // beyond t_max
}

// Against a reference: ray marching with the signed distance (a different
// algorithm).
TEST(Primitives, IntersectionAgreesWithSphereTracing) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (const Primitive& shape : Shapes()) {
    int hits = 0;
    for (int i = 0; i < 400; ++i) {
      const Eigen::Vector3d origin =
          Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized() * 3.0;
      const Eigen::Vector3d target(u(rng) * 0.3, u(rng) * 0.3, u(rng) * 0.3);
      const Eigen::Vector3d dir = (target - origin).normalized();
      const auto hit = Intersect(shape, origin, dir, 0, 100);
      double t = 0;
      bool traced = false;
      for (int step = 0; step < 2000 && t < 10; ++step) {
        const double d = SignedDistance(shape, origin + t * dir);
        if (d < 1e-9) {
          traced = true;
          break;
        }
        t += d;
      }
      ASSERT_EQ(hit.has_value(), traced) << "ray " << i;
      if (!hit) continue;
      ++hits;
      EXPECT_NEAR(hit->t, t, 1e-6);
      EXPECT_NEAR(SignedDistance(shape, origin + hit->t * dir), 0.0, 1e-9);
      EXPECT_NEAR(hit->normal.norm(), 1.0, 1e-9);
      EXPECT_LT(hit->normal.dot(dir), 0.0)
          << "normal must face the incoming ray";
    }
    EXPECT_GT(hits, 50);
  }
}

TEST(Primitives, SamplesAndMeshesLieOnTheSurface) {
  for (const Primitive& shape : Shapes()) {
    std::vector<Eigen::Vector3d> samples;
    AppendSurfaceSamples(shape, 0.01, &samples);
    const double expected = SurfaceArea(shape) / (0.01 * 0.01);
    EXPECT_GT(samples.size(), 0.8 * expected);
    EXPECT_LT(samples.size(), 1.5 * expected);
    for (const auto& p : samples) {
      ASSERT_NEAR(SignedDistance(shape, p), 0.0, 1e-9);
    }
    TriangleMesh mesh;
    AppendMesh(shape, 24, &mesh);
    ASSERT_FALSE(mesh.triangles.empty());
    for (const auto& v : mesh.vertices) {
      // Cap centres of capsules' tubes are inside the capsule; everything else
      // is on it.
      if (std::holds_alternative<Capsule>(shape)) continue;
      ASSERT_NEAR(SignedDistance(shape, v), 0.0, 1e-9);
    }
    const Eigen::AlignedBox3d b = Bounds(shape);
    for (const auto& p : samples) ASSERT_TRUE(b.exteriorDistance(p) < 1e-9);
  }
}

}  // namespace
}  // namespace semrec::synth
