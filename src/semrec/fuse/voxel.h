// Voxel-grid helpers shared by fusion and evaluation: centroid downsampling and
// a hashed grid for exact fixed-radius neighbour search.
#pragma once

#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace semrec::fuse {

using Cloud = std::vector<Eigen::Vector3f>;

/// Integer voxel coordinates packed into one key (21 bits per axis, +-1M
/// voxels).
uint64_t VoxelKey(const Eigen::Vector3f& p, float inv_voxel_size);
uint64_t PackVoxel(int64_t x, int64_t y, int64_t z);

/// One point per occupied voxel: the centroid of the points inside it
/// (accumulated in double), ordered by voxel key, so the result does not depend
/// on the input order.
Cloud VoxelDownsample(const Cloud& points, double voxel_size_m);

/// Points bucketed by cells of `cell_size_m`: every point within cell_size_m of
/// a query lies in the 27 cells around the query's cell.
class VoxelGrid {
 public:
  VoxelGrid() = default;
  VoxelGrid(const Cloud& points, double cell_size_m);

  /// Calls fn(index) for every point in the 27 cells around p (a superset of
  /// the points within cell_size of p), in increasing index order within each
  /// cell.
  template <typename Fn>
  void ForEachNear(const Eigen::Vector3f& p, Fn&& fn) const;

  bool empty() const { return order_.empty(); }

 private:
  // Up to this many cells in the bounding box, cells are a dense array (O(1)
  // look-up); beyond, a sorted list of occupied cells (binary search).
  static constexpr int64_t kMaxDenseCells = 1 << 22;
  // Cell (key, first, count) sorted by key; order_ holds point indices grouped
  // by cell.
  struct Cell {
    uint64_t key;
    uint32_t first;
    uint32_t count;
  };
  const Cell* Find(uint64_t key) const;
  // Calls fn for the points of cell (x, y, z).
  template <typename Fn>
  void ForEachInCell(int64_t x, int64_t y, int64_t z, Fn&& fn) const;

  float inv_cell_ = 1.0f;
  std::vector<Cell> cells_;
  std::vector<uint32_t> order_;
  // Dense mode: cell (x, y, z) holds order_[dense_first_[c] .. dense_first_[c +
  // 1]) with c = ((x - lo_x) * ny + (y - lo_y)) * nz + (z - lo_z).
  bool dense_ = false;
  int64_t lo_[3] = {0, 0, 0};
  int64_t n_[3] = {0, 0, 0};
  std::vector<uint32_t> dense_first_;
};

template <typename Fn>
void VoxelGrid::ForEachInCell(int64_t x, int64_t y, int64_t z, Fn&& fn) const {
  if (dense_) {
    x -= lo_[0], y -= lo_[1], z -= lo_[2];
    if (x < 0 || y < 0 || z < 0 || x >= n_[0] || y >= n_[1] || z >= n_[2]) {
      return;
    }
    const size_t c = static_cast<size_t>((x * n_[1] + y) * n_[2] + z);
    for (uint32_t k = dense_first_[c]; k < dense_first_[c + 1]; ++k) {
      fn(order_[k]);
    }
    return;
  }
  const Cell* cell = Find(PackVoxel(x, y, z));
  if (cell == nullptr) return;
  for (uint32_t k = 0; k < cell->count; ++k) fn(order_[cell->first + k]);
}

template <typename Fn>
void VoxelGrid::ForEachNear(const Eigen::Vector3f& p, Fn&& fn) const {
  const int64_t x = static_cast<int64_t>(std::floor(p.x() * inv_cell_));
  const int64_t y = static_cast<int64_t>(std::floor(p.y() * inv_cell_));
  const int64_t z = static_cast<int64_t>(std::floor(p.z() * inv_cell_));
  // Most queries of a large cloud against a small one are nowhere near it.
  if (dense_ &&
      (x < lo_[0] - 1 || y < lo_[1] - 1 || z < lo_[2] - 1 ||
       x > lo_[0] + n_[0] || y > lo_[1] + n_[1] || z > lo_[2] + n_[2])) {
    return;
  }
  for (int64_t dx = -1; dx <= 1; ++dx) {
    for (int64_t dy = -1; dy <= 1; ++dy) {
      for (int64_t dz = -1; dz <= 1; ++dz) {
        ForEachInCell(x + dx, y + dy, z + dz, fn);
      }
    }
  }
}

}  // namespace semrec::fuse
