// Overlap of two segments' clouds, the paper's sigma = |M| / min(|a|, |b|) with
// M the mutually closest point pairs (each point's nearest neighbour in the
// other cloud, within a distance). Two implementations that return identical
// results: brute force (all |a| x |b| distances, as the paper counts them) and
// a hashed-grid search.
#pragma once

#include <cstdint>

#include "semrec/fuse/voxel.h"

namespace semrec::fuse {

struct OverlapResult {
  /// |M|: pairs (i, j) with nn_b(a_i) = j and nn_a(b_j) = i, both within
  /// max_dist.
  size_t mutual_pairs = 0;
  /// Point-to-point distances evaluated.
  uint64_t distance_computations = 0;
  /// |M| / min(|a|, |b|) (0 for an empty cloud).
  double sigma = 0.0;
};

/// Nearest neighbours are the closest points within max_dist_m; ties go to the
/// lower index.
OverlapResult MutualOverlapBruteForce(const Cloud& a, const Cloud& b,
                                      double max_dist_m);

/// Same result; `grid_b` must be built from `b` with cell size max_dist_m.
OverlapResult MutualOverlapGrid(const Cloud& a, const Cloud& b,
                                const VoxelGrid& grid_b, double max_dist_m);

/// The merge decision sigma > alpha alone, exactly as the full computation
/// would make it, but stopping as soon as it is settled: once |M| > alpha
/// min(|a|, |b|) (accept) or once the points left cannot lift |M| above it
/// (reject). Grids over both clouds (cell size max_dist_m) are built once by
/// the caller. `mutual_pairs` and `sigma` of the result are lower bounds.
struct OverlapDecision {
  bool exceeds = false;
  OverlapResult partial;
};
OverlapDecision MutualOverlapExceeds(const Cloud& a, const VoxelGrid& grid_a,
                                     const Cloud& b, const VoxelGrid& grid_b,
                                     double max_dist_m, double alpha);

}  // namespace semrec::fuse
