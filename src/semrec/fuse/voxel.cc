#include "semrec/fuse/voxel.h"

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <numeric>
#include <unordered_map>

#include "semrec/core/error.h"

namespace semrec::fuse {

uint64_t PackVoxel(int64_t x, int64_t y, int64_t z) {
  constexpr int64_t kOffset = 1 << 20;
  constexpr uint64_t kMask = (1u << 21) - 1;
  return ((static_cast<uint64_t>(x + kOffset) & kMask) << 42) |
         ((static_cast<uint64_t>(y + kOffset) & kMask) << 21) |
         (static_cast<uint64_t>(z + kOffset) & kMask);
}

uint64_t VoxelKey(const Eigen::Vector3f& p, float inv_voxel_size) {
  return PackVoxel(static_cast<int64_t>(std::floor(p.x() * inv_voxel_size)),
                   static_cast<int64_t>(std::floor(p.y() * inv_voxel_size)),
                   static_cast<int64_t>(std::floor(p.z() * inv_voxel_size)));
}

Cloud VoxelDownsample(const Cloud& points, double voxel_size_m) {
  CheckArgument(voxel_size_m > 0.0, "VoxelDownsample: voxel size must be > 0");
  const float inv = static_cast<float>(1.0 / voxel_size_m);
  // Hash accumulation (linear time), then voxels sorted by key: the output
  // order and the summation order (input order within a voxel) are fixed, so
  // results are reproducible.
  struct Accumulator {
    uint64_t key;
    Eigen::Vector3d sum;
    uint32_t count;
  };
  std::vector<Accumulator> voxels;
  std::unordered_map<uint64_t, uint32_t> index;
  index.reserve(points.size() / 4 + 16);
  for (const Eigen::Vector3f& p : points) {
    const uint64_t key = VoxelKey(p, inv);
    const auto [it, inserted] =
        index.try_emplace(key, static_cast<uint32_t>(voxels.size()));
    if (inserted) voxels.push_back({key, Eigen::Vector3d::Zero(), 0});
    Accumulator& acc = voxels[it->second];
    acc.sum += p.cast<double>();
    ++acc.count;
  }
  std::sort(
      voxels.begin(), voxels.end(),
      [](const Accumulator& a, const Accumulator& b) { return a.key < b.key; });
  Cloud out;
  out.reserve(voxels.size());
  for (const Accumulator& v : voxels) {
    out.push_back((v.sum / v.count).cast<float>());
  }
  return out;
}

VoxelGrid::VoxelGrid(const Cloud& points, double cell_size_m) {
  CheckArgument(cell_size_m > 0.0, "VoxelGrid: cell size must be > 0");
  inv_cell_ = static_cast<float>(1.0 / cell_size_m);
  std::vector<std::array<int64_t, 3>> coords(points.size());
  int64_t lo[3] = {INT64_MAX, INT64_MAX, INT64_MAX},
          hi[3] = {INT64_MIN, INT64_MIN, INT64_MIN};
  for (size_t i = 0; i < points.size(); ++i) {
    for (int d = 0; d < 3; ++d) {
      coords[i][d] = static_cast<int64_t>(std::floor(points[i][d] * inv_cell_));
      lo[d] = std::min(lo[d], coords[i][d]);
      hi[d] = std::max(hi[d], coords[i][d]);
    }
  }
  int64_t total = 1;
  for (int d = 0; d < 3 && !points.empty(); ++d) {
    n_[d] = hi[d] - lo[d] + 1;
    lo_[d] = lo[d];
    total = n_[d] > kMaxDenseCells ? kMaxDenseCells + 1 : total * n_[d];
    if (total > kMaxDenseCells) break;
  }
  dense_ = !points.empty() && total <= kMaxDenseCells;
  if (dense_) {
    // Counting sort into cells; points keep their index order within a cell.
    dense_first_.assign(static_cast<size_t>(total) + 1, 0);
    std::vector<uint32_t> cell_of(points.size());
    for (size_t i = 0; i < points.size(); ++i) {
      cell_of[i] = static_cast<uint32_t>(
          ((coords[i][0] - lo_[0]) * n_[1] + (coords[i][1] - lo_[1])) * n_[2] +
          (coords[i][2] - lo_[2]));
      ++dense_first_[cell_of[i] + 1];
    }
    for (size_t c = 1; c < dense_first_.size(); ++c) {
      dense_first_[c] += dense_first_[c - 1];
    }
    order_.resize(points.size());
    std::vector<uint32_t> fill(dense_first_.begin(), dense_first_.end() - 1);
    for (size_t i = 0; i < points.size(); ++i) {
      order_[fill[cell_of[i]]++] = static_cast<uint32_t>(i);
    }
    return;
  }
  std::vector<std::pair<uint64_t, uint32_t>> keyed(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    keyed[i] = {PackVoxel(coords[i][0], coords[i][1], coords[i][2]),
                static_cast<uint32_t>(i)};
  }
  std::sort(keyed.begin(), keyed.end());
  order_.resize(keyed.size());
  for (size_t i = 0; i < keyed.size(); ++i) {
    order_[i] = keyed[i].second;
    if (cells_.empty() || cells_.back().key != keyed[i].first) {
      cells_.push_back({keyed[i].first, static_cast<uint32_t>(i), 0});
    }
    ++cells_.back().count;
  }
}

const VoxelGrid::Cell* VoxelGrid::Find(uint64_t key) const {
  auto it =
      std::lower_bound(cells_.begin(), cells_.end(), key,
                       [](const Cell& c, uint64_t k) { return c.key < k; });
  return it != cells_.end() && it->key == key ? &*it : nullptr;
}

}  // namespace semrec::fuse
