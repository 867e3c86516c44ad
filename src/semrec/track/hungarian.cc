#include "semrec/track/hungarian.h"

#include <algorithm>
#include <cmath>

#include "semrec/core/error.h"

namespace semrec::track {
namespace {

// Square or wide (rows <= cols) matrix, all entries finite: classic
// potentials-based Hungarian method (Kuhn-Munkres with Dijkstra-like
// augmentation). Returns the column of each row.
std::vector<int> SolveDense(const Eigen::MatrixXd& a) {
  const int n = static_cast<int>(a.rows()), m = static_cast<int>(a.cols());
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> u(n + 1, 0.0), v(m + 1, 0.0), min_v(m + 1);
  std::vector<int> p(m + 1, 0),
      way(m + 1, 0);  // p[j]: row (1-based) matched to column j
  std::vector<char> used(m + 1);
  for (int i = 1; i <= n; ++i) {
    p[0] = i;
    int j0 = 0;
    std::fill(min_v.begin(), min_v.end(), inf);
    std::fill(used.begin(), used.end(), 0);
    do {
      used[j0] = 1;
      const int i0 = p[j0];
      double delta = inf;
      int j1 = 0;
      for (int j = 1; j <= m; ++j) {
        if (used[j]) continue;
        const double cur = a(i0 - 1, j - 1) - u[i0] - v[j];
        if (cur < min_v[j]) min_v[j] = cur, way[j] = j0;
        if (min_v[j] < delta) delta = min_v[j], j1 = j;
      }
      for (int j = 0; j <= m; ++j) {
        if (used[j]) {
          u[p[j]] += delta;
          v[j] -= delta;
        } else {
          min_v[j] -= delta;
        }
      }
      j0 = j1;
    } while (p[j0] != 0);
    do {
      const int j1 = way[j0];
      p[j0] = p[j1];
      j0 = j1;
    } while (j0 != 0);
  }
  std::vector<int> col_of_row(n, -1);
  for (int j = 1; j <= m; ++j) {
    if (p[j] != 0) col_of_row[p[j] - 1] = j - 1;
  }
  return col_of_row;
}

}  // namespace

Assignment SolveAssignment(const Eigen::MatrixXd& cost) {
  Assignment result;
  const int rows = static_cast<int>(cost.rows()),
            cols = static_cast<int>(cost.cols());
  if (rows == 0 || cols == 0) return result;
  double max_finite = 0.0;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const double x = cost(r, c);
      CheckArgument(!std::isnan(x), "assignment: cost matrix contains NaN");
      if (std::isfinite(x)) max_finite = std::max(max_finite, std::abs(x));
    }
  }
  // Forbidden entries become a penalty larger than any sum of finite costs, so
  // the optimum first maximises the number of allowed pairs, then minimises
  // their cost; pairs that still use a penalty entry are dropped afterwards.
  // Padding to rows <= cols keeps it rectangular.
  const int n = std::min(rows, cols);
  const double penalty = (max_finite + 1.0) * (n + 1) * 2.0;
  const bool transpose = rows > cols;
  Eigen::MatrixXd a = transpose ? Eigen::MatrixXd(cost.transpose()) : cost;
  for (int r = 0; r < a.rows(); ++r) {
    for (int c = 0; c < a.cols(); ++c) {
      if (!std::isfinite(a(r, c))) a(r, c) = penalty;
    }
  }
  const std::vector<int> col_of_row = SolveDense(a);
  for (int r = 0; r < static_cast<int>(col_of_row.size()); ++r) {
    const int c = col_of_row[r];
    if (c < 0 || a(r, c) >= penalty) continue;
    result.pairs.emplace_back(transpose ? c : r, transpose ? r : c);
    result.cost += a(r, c);
  }
  std::sort(result.pairs.begin(), result.pairs.end());
  return result;
}

}  // namespace semrec::track
