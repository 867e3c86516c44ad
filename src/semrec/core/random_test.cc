#include "semrec/core/random.h"

#include <cmath>

#include <gtest/gtest.h>

namespace semrec {
namespace {

TEST(Rng, ReproducibleAndSeedDependent) {
  Rng a(42), b(42), c(43);
  for (int i = 0; i < 100; ++i) {
    const uint64_t x = a.Next();
    EXPECT_EQ(x, b.Next());
    EXPECT_NE(x, c.Next());
  }
}

TEST(Rng, DistributionMoments) {
  Rng rng(7);
  const int n = 200000;
  double su = 0, sn = 0, sn2 = 0;
  int64_t lo = 100, hi = -100;
  for (int i = 0; i < n; ++i) {
    const double u = rng.Uniform();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    su += u;
    const double z = rng.Normal();
    sn += z;
    sn2 += z * z;
    const int64_t k = rng.UniformInt(-3, 3);
    lo = std::min(lo, k), hi = std::max(hi, k);
  }
  EXPECT_NEAR(su / n, 0.5, 0.005);
  EXPECT_NEAR(sn / n, 0.0, 0.01);
  EXPECT_NEAR(std::sqrt(sn2 / n), 1.0, 0.01);
  EXPECT_EQ(lo, -3);
  EXPECT_EQ(hi, 3);
}

}  // namespace
}  // namespace semrec
