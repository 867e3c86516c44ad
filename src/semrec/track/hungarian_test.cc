#include "semrec/track/hungarian.h"

#include <algorithm>
#include <numeric>
#include <random>

#include <gtest/gtest.h>

namespace semrec::track {
namespace {

// Reference: try every injective map of the smaller side into the larger one;
// best = most allowed pairs, then least cost.
std::pair<int, double> BruteForce(const Eigen::MatrixXd& cost) {
  const bool t = cost.rows() > cost.cols();
  const Eigen::MatrixXd a = t ? Eigen::MatrixXd(cost.transpose()) : cost;
  const int n = static_cast<int>(a.rows()), m = static_cast<int>(a.cols());
  std::vector<int> cols(m);
  std::iota(cols.begin(), cols.end(), 0);
  int best_pairs = -1;
  double best_cost = 0.0;
  do {
    int pairs = 0;
    double c = 0.0;
    for (int r = 0; r < n; ++r) {
      if (std::isfinite(a(r, cols[r]))) ++pairs, c += a(r, cols[r]);
    }
    if (pairs > best_pairs || (pairs == best_pairs && c < best_cost - 1e-12)) {
      best_pairs = pairs, best_cost = c;
    }
  } while (std::next_permutation(cols.begin(), cols.end()));
  return {best_pairs, best_cost};
}

TEST(Hungarian, MatchesBruteForceOnRandomRectangularMatrices) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(0.0, 10.0);
  for (int trial = 0; trial < 300; ++trial) {
    const int rows = 1 + trial % 6, cols = 1 + (trial / 6) % 6;
    Eigen::MatrixXd cost(rows, cols);
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < cols; ++c) {
        cost(r, c) = (trial % 3 == 0 && u(rng) < 3.0)
                         ? kForbidden
                         : std::round(u(rng) * 4) / 4;
      }
    }
    const Assignment a = SolveAssignment(cost);
    const auto [pairs, best] = BruteForce(cost);
    ASSERT_EQ(static_cast<int>(a.pairs.size()), pairs)
        << "trial " << trial << "\n"
        << cost;
    ASSERT_NEAR(a.cost, best, 1e-9) << "trial " << trial << "\n" << cost;
    std::vector<int> seen_cols;
    for (const auto& [r, c] : a.pairs) {
      ASSERT_TRUE(std::isfinite(cost(r, c)));
      seen_cols.push_back(c);
    }
    std::sort(seen_cols.begin(), seen_cols.end());
    ASSERT_TRUE(std::adjacent_find(seen_cols.begin(), seen_cols.end()) ==
                seen_cols.end());
  }
}

TEST(Hungarian, EdgeCases) {
  EXPECT_TRUE(SolveAssignment(Eigen::MatrixXd(0, 3)).pairs.empty());
  Eigen::MatrixXd all_forbidden = Eigen::MatrixXd::Constant(2, 2, kForbidden);
  EXPECT_TRUE(SolveAssignment(all_forbidden).pairs.empty());
  Eigen::MatrixXd nan(1, 1);
  nan(0, 0) = std::nan("");
  EXPECT_THROW(SolveAssignment(nan), std::exception);
  Eigen::MatrixXd negative(2, 2);
  negative << -1, -5, -3, -2;
  const Assignment a = SolveAssignment(negative);
  EXPECT_DOUBLE_EQ(a.cost, -8.0);  // (0,1) + (1,0)
}

}  // namespace
}  // namespace semrec::track
