#include "semrec/eval/c2c.h"

#include <algorithm>
#include <cmath>

#include <tbb/parallel_for.h>
#include <nanoflann.hpp>

#include "semrec/core/error.h"

namespace semrec::eval {
namespace {

struct CloudAdaptor {
  const std::vector<Eigen::Vector3f>& points;
  size_t kdtree_get_point_count() const { return points.size(); }
  float kdtree_get_pt(size_t i, size_t dim) const { return points[i][dim]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

using KdTree = nanoflann::KDTreeSingleIndexAdaptor<
    nanoflann::L2_Simple_Adaptor<float, CloudAdaptor, double>, CloudAdaptor, 3,
    size_t>;

}  // namespace

std::vector<std::pair<size_t, double>> NearestNeighbors(
    const std::vector<Eigen::Vector3f>& queries,
    const std::vector<Eigen::Vector3f>& reference) {
  CheckArgument(!reference.empty(),
                "nearest neighbours: the reference cloud is empty");
  const CloudAdaptor adaptor{reference};
  KdTree tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tree.buildIndex();
  std::vector<std::pair<size_t, double>> out(queries.size());
  tbb::parallel_for(size_t{0}, queries.size(), [&](size_t i) {
    size_t index = 0;
    double d2 = 0.0;
    nanoflann::KNNResultSet<double, size_t> result(1);
    result.init(&index, &d2);
    tree.findNeighbors(result, queries[i].data(), nanoflann::SearchParams());
    // Recompute in double from the points themselves (the tree's metric is
    // exact, this only fixes the precision of the reported value).
    out[i] = {
        index,
        (queries[i].cast<double>() - reference[index].cast<double>()).norm()};
  });
  return out;
}

std::vector<double> CloudToCloudDistances(
    const std::vector<Eigen::Vector3f>& estimate,
    const std::vector<Eigen::Vector3f>& reference) {
  CheckArgument(!reference.empty(),
                "cloud-to-cloud distance: the reference cloud is empty");
  const auto nearest = NearestNeighbors(estimate, reference);
  std::vector<double> out(nearest.size());
  for (size_t i = 0; i < nearest.size(); ++i) out[i] = nearest[i].second;
  return out;
}

DistanceStats Summarize(std::vector<double> d) {
  DistanceStats s;
  s.count = d.size();
  if (d.empty()) return s;
  double sum = 0.0, sum2 = 0.0;
  for (double x : d) {
    sum += x;
    sum2 += x * x;
    s.max_m = std::max(s.max_m, x);
  }
  s.mean_m = sum / d.size();
  s.rms_m = std::sqrt(sum2 / d.size());
  double var = 0.0;
  for (double x : d) var += (x - s.mean_m) * (x - s.mean_m);
  s.std_m = d.size() > 1 ? std::sqrt(var / (d.size() - 1)) : 0.0;
  const size_t mid = d.size() / 2;
  std::nth_element(d.begin(), d.begin() + mid, d.end());
  s.median_m = d[mid];
  if (d.size() % 2 == 0) {
    s.median_m =
        (s.median_m + *std::max_element(d.begin(), d.begin() + mid)) / 2;
  }
  return s;
}

}  // namespace semrec::eval
