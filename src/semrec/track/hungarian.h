// Minimum-cost assignment (the Hungarian method, O(n^2 m) with potentials and
// shortest augmenting paths) for rectangular cost matrices with forbidden
// entries.
#pragma once

#include <limits>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace semrec::track {

/// Forbidden pairs carry this cost (any non-finite value is treated the same).
constexpr double kForbidden = std::numeric_limits<double>::infinity();

struct Assignment {
  /// (row, column) pairs, sorted by row.
  std::vector<std::pair<int, int>> pairs;
  double cost = 0.0;
};

/// Among the assignments that match as many pairs as possible without forbidden
/// entries, one of minimum total cost. Rows or columns may stay unassigned
/// (rectangular matrices, forbidden entries). Throws InvalidArgument for NaN
/// costs.
Assignment SolveAssignment(const Eigen::MatrixXd& cost);

}  // namespace semrec::track
