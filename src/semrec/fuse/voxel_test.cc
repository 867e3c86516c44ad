#include "semrec/fuse/voxel.h"

#include <random>
#include <set>

#include <gtest/gtest.h>

namespace semrec::fuse {
namespace {

TEST(VoxelDownsample, CentroidPerVoxelIndependentOfOrder) {
  Cloud points = {{0.01f, 0.01f, 0.01f},
                  {0.03f, 0.05f, 0.07f},
                  {0.15f, 0.0f, 0.0f},
                  {-0.01f, 0.0f, 0.0f}};
  const Cloud down = VoxelDownsample(points, 0.1);
  ASSERT_EQ(down.size(), 3u);  // voxels (0,0,0), (1,0,0), (-1,0,0)
  bool found = false;
  for (const auto& p : down) {
    if ((p - Eigen::Vector3f(0.02f, 0.03f, 0.04f)).norm() < 1e-6f) found = true;
  }
  EXPECT_TRUE(found);
  std::reverse(points.begin(), points.end());
  EXPECT_EQ(VoxelDownsample(points, 0.1), down);
}

class VoxelGridModes : public ::testing::TestWithParam<bool> {};

// The brute-force definition: closest point with d2 <= max_d2, ties to the
// lower index.
Neighbor BruteNearest(const Cloud& points, const Eigen::Vector3f& q,
                      float max_d2) {
  Neighbor best;
  for (size_t i = 0; i < points.size(); ++i) {
    const float d2 = SquaredDistance(q, points[i]);
    if (d2 <= max_d2 && (best.index < 0 || d2 < best.d2)) {
      best = {d2, static_cast<int64_t>(i)};
    }
  }
  return best;
}

// Dense (compact clouds) and sparse (a far outlier makes the box huge) modes
// agree with brute force, on random points and on a lattice full of exact
// ties, with far fewer distance evaluations.
TEST_P(VoxelGridModes, NearestMatchesBruteForce) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  Cloud points(2000);
  for (auto& p : points) p = {u(rng), u(rng), u(rng)};
  // Lattice points 0.125 m apart (exact in float) and duplicates: equal
  // distances from lattice-aligned queries.
  for (int x = 0; x < 8; ++x) {
    for (int y = 0; y < 8; ++y) {
      points.push_back({0.125f * x, 0.125f * y, 0.5f});
      if ((x + y) % 3 == 0) points.push_back(points.back());
    }
  }
  if (GetParam()) points.push_back({3000.0f, -3000.0f, 3000.0f});
  const float radius = 0.15f;
  const VoxelGrid grid(points, radius);
  std::vector<Eigen::Vector3f> queries;
  for (int q = 0; q < 300; ++q) queries.push_back({u(rng), u(rng), u(rng)});
  for (int x = 0; x < 8; ++x) {
    queries.push_back({0.125f * x + 0.0625f, 0.125f, 0.5f});  // midway: a tie
    queries.push_back({0.125f * x, 0.125f * x, 0.5f + 0.125f});
  }
  queries.push_back({5.0f, 5.0f, 5.0f});  // nothing near
  uint64_t evaluated = 0;
  for (const float max_d2 : {radius * radius, 0.125f * 0.125f, 0.01f}) {
    for (const auto& q : queries) {
      const Neighbor g = grid.Nearest(points, q, max_d2, &evaluated);
      const Neighbor b = BruteNearest(points, q, max_d2);
      ASSERT_EQ(g.index, b.index) << q.transpose() << " max_d2 " << max_d2;
      if (b.index >= 0) {
        ASSERT_EQ(g.d2, b.d2);
      }
    }
  }
  EXPECT_LT(evaluated, 3 * queries.size() * points.size() / 50);
  EXPECT_EQ(VoxelGrid().Nearest(points, queries[0], 1.0f, &evaluated).index,
            -1);
}

INSTANTIATE_TEST_SUITE_P(DenseAndSparse, VoxelGridModes,
                         ::testing::Values(false, true));

}  // namespace
}  // namespace semrec::fuse
