#include "semrec/fuse/overlap.h"

#include <random>

#include <gtest/gtest.h>

namespace semrec::fuse {
namespace {

TEST(Overlap, HandWorkedExample) {
  // a0-b0 mutual (0.02), a1's nearest is b0 but b0 prefers a0: not mutual; a2
  // far from all.
  const Cloud a = {{0, 0, 0}, {0.05f, 0, 0}, {5, 5, 5}};
  const Cloud b = {{0.02f, 0, 0}, {0.2f, 0, 0}};
  const OverlapResult r = MutualOverlapBruteForce(a, b, 0.1);
  EXPECT_EQ(r.mutual_pairs, 1u);
  EXPECT_EQ(r.distance_computations, 6u);
  EXPECT_DOUBLE_EQ(r.sigma, 0.5);  // 1 / min(3, 2)
  const OverlapResult g = MutualOverlapGrid(a, b, VoxelGrid(b, 0.1), 0.1);
  EXPECT_EQ(g.mutual_pairs, 1u);
  EXPECT_DOUBLE_EQ(g.sigma, 0.5);
  EXPECT_EQ(MutualOverlapBruteForce(a, {}, 0.1).sigma, 0.0);
}

// The grid search must give exactly the brute-force answer, also with ties
// (points on a grid).
TEST(Overlap, GridEqualsBruteForceOnRandomClouds) {
  std::mt19937 rng(9);
  for (int trial = 0; trial < 60; ++trial) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const bool lattice = trial % 3 == 0;
    auto make = [&](int n, float shift) {
      Cloud c(n);
      for (auto& p : c) {
        p = {u(rng), u(rng), u(rng) * 0.3f};
        if (lattice) p = (p * 20).array().round() / 20;  // exact ties
        p.x() += shift;
      }
      return c;
    };
    const Cloud a = make(50 + trial * 7, 0.0f);
    const Cloud b = make(80 + trial * 3, 0.3f * (trial % 4));
    const double max_dist = 0.05 + 0.01 * (trial % 5);
    const OverlapResult brute = MutualOverlapBruteForce(a, b, max_dist);
    const OverlapResult grid =
        MutualOverlapGrid(a, b, VoxelGrid(b, max_dist), max_dist);
    ASSERT_EQ(brute.mutual_pairs, grid.mutual_pairs) << "trial " << trial;
    ASSERT_EQ(brute.sigma, grid.sigma);
    EXPECT_LE(grid.distance_computations, brute.distance_computations);
    // The early-stopping decision equals the full one at every threshold,
    // including the boundary alpha = sigma (sigma > alpha is false there).
    const VoxelGrid grid_a(a, max_dist), grid_b(b, max_dist);
    for (double alpha : {0.0, 0.1, 0.3, 0.5, 0.7, 0.9, brute.sigma}) {
      if (alpha >= 1.0) continue;
      const OverlapDecision d =
          MutualOverlapExceeds(a, grid_a, b, grid_b, max_dist, alpha);
      ASSERT_EQ(d.exceeds, brute.sigma > alpha)
          << "trial " << trial << " alpha " << alpha;
      EXPECT_LE(d.partial.mutual_pairs, brute.mutual_pairs);
    }
  }
}

}  // namespace
}  // namespace semrec::fuse
