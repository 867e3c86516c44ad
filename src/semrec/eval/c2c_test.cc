#include "semrec/eval/c2c.h"

#include <random>

#include <gtest/gtest.h>

#include "semrec/core/error.h"

namespace semrec::eval {
namespace {

TEST(C2C, MatchesBruteForceNearestNeighbour) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-1, 1);
  std::vector<Eigen::Vector3f> ref(3000), est(500);
  for (auto& p : ref) p = {u(rng), u(rng), u(rng)};
  for (auto& p : est) p = {u(rng) * 1.2f, u(rng) * 1.2f, u(rng) * 1.2f};
  const auto d = CloudToCloudDistances(est, ref);
  ASSERT_EQ(d.size(), est.size());
  for (size_t i = 0; i < est.size(); ++i) {
    double best = 1e9;
    for (const auto& r : ref) {
      best = std::min(best, (est[i].cast<double>() - r.cast<double>()).norm());
    }
    ASSERT_NEAR(d[i], best, 1e-12);
  }
  EXPECT_THROW(CloudToCloudDistances(est, {}), InvalidArgument);
}

TEST(C2C, Summary) {
  const DistanceStats s = Summarize({0.001, 0.002, 0.003, 0.010});
  EXPECT_EQ(s.count, 4u);
  EXPECT_DOUBLE_EQ(s.mean_m, 0.004);
  EXPECT_DOUBLE_EQ(s.max_m, 0.010);
  EXPECT_DOUBLE_EQ(s.median_m, 0.0025);
  EXPECT_NEAR(s.std_m, std::sqrt((9e-6 + 4e-6 + 1e-6 + 36e-6) / 3), 1e-15);
}

}  // namespace
}  // namespace semrec::eval
