// Cloud-to-cloud distance, as CloudCompare's C2C computes it: for each point of
// the estimate, the Euclidean distance to the nearest point of the reference
// (exact nearest neighbour).
#pragma once

#include <cstddef>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace semrec::eval {

/// Distance (m) from each estimate point to its nearest reference point. Throws
/// InvalidArgument when the reference is empty.
/// For every query point, the index of its nearest reference point and the
/// distance (exact, k-d tree). Throws InvalidArgument for an empty reference.
std::vector<std::pair<size_t, double>> NearestNeighbors(
    const std::vector<Eigen::Vector3f>& queries,
    const std::vector<Eigen::Vector3f>& reference);

std::vector<double> CloudToCloudDistances(
    const std::vector<Eigen::Vector3f>& estimate,
    const std::vector<Eigen::Vector3f>& reference);

struct DistanceStats {
  size_t count = 0;
  double mean_m = 0.0;
  /// Sample standard deviation (n - 1), as CloudCompare reports.
  double std_m = 0.0;
  double median_m = 0.0;
  double max_m = 0.0;
  double rms_m = 0.0;
};
DistanceStats Summarize(std::vector<double> distances);

}  // namespace semrec::eval
