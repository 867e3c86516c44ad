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

// Dense (compact clouds) and sparse (a far outlier makes the box huge) modes
// agree with brute force.
TEST_P(VoxelGridModes, NeighboursMatchBruteForce) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  Cloud points(2000);
  for (auto& p : points) p = {u(rng), u(rng), u(rng)};
  if (GetParam()) points.push_back({3000.0f, -3000.0f, 3000.0f});
  const float radius = 0.15f;
  const VoxelGrid grid(points, radius);
  for (int q = 0; q < 200; ++q) {
    const Eigen::Vector3f query(u(rng), u(rng), u(rng));
    std::set<uint32_t> near_grid, near_brute;
    grid.ForEachNear(query, [&](uint32_t i) {
      if ((points[i] - query).norm() <= radius) near_grid.insert(i);
    });
    for (uint32_t i = 0; i < points.size(); ++i) {
      if ((points[i] - query).norm() <= radius) near_brute.insert(i);
    }
    ASSERT_EQ(near_grid, near_brute);
  }
}

INSTANTIATE_TEST_SUITE_P(DenseAndSparse, VoxelGridModes,
                         ::testing::Values(false, true));

}  // namespace
}  // namespace semrec::fuse
