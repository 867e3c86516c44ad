// Voxel-grid helpers shared by fusion and evaluation: centroid downsampling and
// a hashed grid for exact fixed-radius neighbour search.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace semrec::fuse {

using Cloud = std::vector<Eigen::Vector3f>;

/// Axis-aligned bounds of a cloud (empty for an empty cloud).
Eigen::AlignedBox3f BoundsOf(const Cloud& cloud);

/// True when boxes grown by `margin_m` touch: clouds whose boxes are farther
/// apart than a distance share no point pair within it.
inline bool BoxesWithin(const Eigen::AlignedBox3f& a,
                        const Eigen::AlignedBox3f& b, float margin_m) {
  return (a.min().array() - margin_m <= b.max().array()).all() &&
         (b.min().array() - margin_m <= a.max().array()).all();
}

/// Integer voxel coordinates packed into one key (21 bits per axis, +-1M
/// voxels).
uint64_t VoxelKey(const Eigen::Vector3f& p, float inv_voxel_size);
uint64_t PackVoxel(int64_t x, int64_t y, int64_t z);
/// Integer voxel coordinates of a key (inverse of PackVoxel).
Eigen::Vector3i UnpackVoxel(uint64_t key);

/// One point per occupied voxel: the centroid of the points inside it
/// (accumulated in double), ordered by voxel key, so the result does not depend
/// on the input order.
Cloud VoxelDownsample(const Cloud& points, double voxel_size_m);

/// Squared Euclidean distance; every exact search uses this one float
/// expression, so that ties and thresholds agree bit for bit.
inline float SquaredDistance(const Eigen::Vector3f& p,
                             const Eigen::Vector3f& q) {
  const float dx = p.x() - q.x(), dy = p.y() - q.y(), dz = p.z() - q.z();
  return dx * dx + dy * dy + dz * dz;
}

/// The one tie rule of every exact nearest-neighbour search (brute force and
/// grid agree on it): candidate (d2, i) beats (best_d2, best_i) when nearer,
/// or as near with a lower index.
inline bool Nearer(float d2, int64_t i, float best_d2, int64_t best_i) {
  return d2 < best_d2 || (d2 == best_d2 && i < best_i);
}

/// A nearest-neighbour result: index -1 (and d2 infinite) when none was within
/// reach.
struct Neighbor {
  float d2 = std::numeric_limits<float>::infinity();
  int64_t index = -1;
  /// Keeps candidate i when Nearer().
  void Offer(float d, int64_t i) {
    if (Nearer(d, i, d2, index)) d2 = d, index = i;
  }
};

/// Points bucketed by cells of `cell_size_m`: every point within cell_size_m of
/// a query lies in the 27 cells around the query's cell. Exact nearest
/// neighbour search within that radius.
class VoxelGrid {
 public:
  VoxelGrid() = default;
  VoxelGrid(const Cloud& points, double cell_size_m);

  /// The nearest of `points` (the cloud this grid was built from) to p with
  /// squared distance <= max_d2 (max_d2 <= cell_size^2); ties go to the lower
  /// index, as in a brute-force scan. Searches p's own cell first and skips
  /// neighbour cells farther away than the best point so far; adds the
  /// distances it evaluated to *computations.
  Neighbor Nearest(const Cloud& points, const Eigen::Vector3f& p, float max_d2,
                   uint64_t* computations) const;

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

}  // namespace semrec::fuse
