#include "semrec/fuse/voxel.h"

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <numeric>
#include <unordered_map>

#include "semrec/core/error.h"

namespace semrec::fuse {

Eigen::AlignedBox3f BoundsOf(const Cloud& cloud) {
  Eigen::AlignedBox3f box;
  for (const auto& p : cloud) box.extend(p);
  return box;
}

namespace {
// 21 bits per axis, offset so that negative coordinates pack.
constexpr int64_t kOffset = 1 << 20;
constexpr uint64_t kMask = (1u << 21) - 1;
}  // namespace

uint64_t PackVoxel(int64_t x, int64_t y, int64_t z) {
  return ((static_cast<uint64_t>(x + kOffset) & kMask) << 42) |
         ((static_cast<uint64_t>(y + kOffset) & kMask) << 21) |
         (static_cast<uint64_t>(z + kOffset) & kMask);
}

Eigen::Vector3i UnpackVoxel(uint64_t key) {
  auto axis = [key](int shift) {
    return static_cast<int>(static_cast<int64_t>((key >> shift) & kMask) -
                            kOffset);
  };
  return {axis(42), axis(21), axis(0)};
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

Neighbor VoxelGrid::Nearest(const Cloud& points, const Eigen::Vector3f& p,
                            float max_d2, uint64_t* computations) const {
  Neighbor best;
  if (order_.empty()) return best;
  const float fx = p.x() * inv_cell_, fy = p.y() * inv_cell_,
              fz = p.z() * inv_cell_;
  const int64_t cell[3] = {static_cast<int64_t>(std::floor(fx)),
                           static_cast<int64_t>(std::floor(fy)),
                           static_cast<int64_t>(std::floor(fz))};
  if (dense_) {
    for (int d = 0; d < 3; ++d) {
      const int64_t r = cell[d] - lo_[d];
      if (r < -1 || r > n_[d]) return best;  // nowhere near the cloud
    }
  }
  // Per axis, the gap from p to the neighbour cells below and above, shrunk
  // by 0.1% of a cell so that float rounding of the boundaries can never skip
  // a cell holding a point within the best distance.
  const float cell_size = 1.0f / inv_cell_;
  const float slack = 1e-3f;
  float gap[3][3];
  const float frac[3] = {fx - static_cast<float>(cell[0]),
                         fy - static_cast<float>(cell[1]),
                         fz - static_cast<float>(cell[2])};
  for (int d = 0; d < 3; ++d) {
    const float below = std::max(0.0f, frac[d] - slack) * cell_size;
    const float above = std::max(0.0f, 1.0f - frac[d] - slack) * cell_size;
    gap[d][0] = below * below;
    gap[d][1] = 0.0f;
    gap[d][2] = above * above;
  }
  uint64_t evaluated = 0;
  auto visit = [&](int64_t x, int64_t y, int64_t z) {
    const uint32_t* first = nullptr;
    const uint32_t* last = nullptr;
    if (dense_) {
      x -= lo_[0], y -= lo_[1], z -= lo_[2];
      if (x < 0 || y < 0 || z < 0 || x >= n_[0] || y >= n_[1] || z >= n_[2]) {
        return;
      }
      const size_t c = static_cast<size_t>((x * n_[1] + y) * n_[2] + z);
      first = order_.data() + dense_first_[c];
      last = order_.data() + dense_first_[c + 1];
    } else {
      const Cell* found = Find(PackVoxel(x, y, z));
      if (found == nullptr) return;
      first = order_.data() + found->first;
      last = first + found->count;
    }
    for (const uint32_t* k = first; k != last; ++k) {
      const float d2 = SquaredDistance(p, points[*k]);
      ++evaluated;
      if (d2 <= max_d2) best.Offer(d2, *k);
    }
  };
  visit(cell[0], cell[1], cell[2]);
  for (int dx = 0; dx < 3; ++dx) {
    for (int dy = 0; dy < 3; ++dy) {
      const float gxy = gap[0][dx] + gap[1][dy];
      for (int dz = 0; dz < 3; ++dz) {
        if (dx == 1 && dy == 1 && dz == 1) continue;  // own cell, done
        if (gxy + gap[2][dz] > std::min(best.d2, max_d2)) continue;
        visit(cell[0] + dx - 1, cell[1] + dy - 1, cell[2] + dz - 1);
      }
    }
  }
  *computations += evaluated;
  return best;
}

}  // namespace semrec::fuse
