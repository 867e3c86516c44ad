// Semantics-guided point-cloud fusion (the paper's Section II-C).
//
// Each new frame's segments are compared with the scene's segments of the same
// class (label gating): both clouds are voxel-downsampled at corr_voxel_size_m,
// M = mutually closest point pairs within max_corr_dist_m, sigma = |M| /
// min(|a|, |b|); sigma > alpha means "same object".
//
// Merge rule: all frame segments are compared with the scene as it was before
// the frame (so the comparisons are independent and run in parallel). A frame
// segment that matches several scene segments merges them all; scene segments
// linked through any frame segment end as one segment (union-find), which keeps
// the smallest id, the earliest first-seen frame and the summed observations.
// Unmatched frame segments become new scene segments, in frame-segment order.
// Frame segments are first downsampled at store_voxel_size_m (their comparison
// cloud is derived from that); merged clouds are the union of the members'
// stored points, downsampled again at store_voxel_size_m. With gating off, a
// merged segment takes the class holding most of its points (ties: the smaller
// class id).
//
// Structure: segments of a "stuff" class (wall, floor, ceiling...) are not
// objects. With `stuff_per_class`, all of a frame's segments of one stuff
// class become one, and it merges into the scene's segment of that class
// without an overlap test: one segment per stuff class (walls on opposite
// sides of a room never overlap, yet they are the same structure).
#pragma once

#include <cstdint>
#include <map>
#include <vector>

#include <Eigen/Geometry>

#include "semrec/fuse/segments.h"
#include "semrec/fuse/voxel.h"

namespace semrec::fuse {

struct FusionOptions {
  enum class Method {
    /// Hashed-grid neighbour search, bounding-box rejection, TBB over frame
    /// segments.
    kFast,
    /// All pairwise distances, as the paper counts them; same decisions as
    /// kFast.
    kBruteForce,
  };
  /// Voxel size for the overlap test (the paper's 100 mm).
  double corr_voxel_size_m = 0.10;
  /// Voxel size of the stored clouds (the paper's 50 mm).
  double store_voxel_size_m = 0.05;
  /// Mutually closest pairs farther apart than this do not count: one
  /// comparison voxel, so that only surfaces that actually coincide overlap.
  double max_corr_dist_m = 0.10;
  /// Merge when sigma > alpha.
  double alpha = 0.5;
  /// Compare only segments of the same class (off: compare with every scene
  /// segment).
  bool label_gating = true;
  /// One scene segment per stuff class (see above); off: stuff is fused like
  /// objects (the paper).
  bool stuff_per_class = true;
  Method method = Method::kFast;

  void Check() const;
};

struct SceneSegment {
  uint32_t id = 0;
  uint16_t class_id = 0;
  /// Stored cloud (world frame), downsampled at store_voxel_size_m.
  Cloud points;
  size_t first_seen_frame = 0;
  size_t last_seen_frame = 0;
  /// Frame segments merged into this one (including the first).
  size_t observations = 0;
  /// The cloud at corr_voxel_size_m and its bounds, for the overlap test.
  Cloud corr_points;
  Eigen::AlignedBox3f bounds;
  VoxelGrid corr_grid;
};

struct FrameFusionStats {
  size_t frame_index = 0;
  size_t frame_segments = 0;
  size_t scene_segments_before = 0;
  /// Points at the comparison resolution.
  size_t frame_points = 0;
  size_t scene_points = 0;
  /// Pairs (frame segment, scene segment) that were compared.
  size_t compared_pairs = 0;
  /// |a| x |b| summed over all pairs (what brute force computes) without and
  /// with label gating, whatever the method: their ratio is the paper's
  /// reduction factor.
  uint64_t distance_computations_ungated = 0;
  uint64_t distance_computations_gated = 0;
  /// Distances this run actually evaluated.
  uint64_t distance_computations_done = 0;
  size_t merged_frame_segments = 0;
  size_t new_segments = 0;
  size_t removed_by_merge = 0;
  /// Whole Integrate() call, and its comparison stage alone (the overlap
  /// tests).
  double seconds = 0.0;
  double compare_seconds = 0.0;
  /// For each input frame segment, the id of the scene segment it ended in
  /// (later merges may absorb that id: SceneFusion::ResolveId gives the current
  /// one).
  std::vector<uint32_t> assigned_ids;
};

class SceneFusion {
 public:
  explicit SceneFusion(const FusionOptions& options = {});

  /// Fuses one frame's segments (from ExtractFrameSegments) into the scene.
  FrameFusionStats Integrate(const std::vector<FrameSegment>& frame_segments,
                             size_t frame_index);

  /// Scene segments, sorted by id.
  const std::vector<SceneSegment>& segments() const { return segments_; }
  const FusionOptions& options() const { return options_; }

  /// The current id of the segment that segment `id` was merged into (itself if
  /// it was not).
  uint32_t ResolveId(uint32_t id) const;

 private:
  FusionOptions options_;
  std::vector<SceneSegment> segments_;
  uint32_t next_id_ = 1;
  /// Absorbed segment id -> the id it was merged into.
  std::map<uint32_t, uint32_t> merged_into_;
};

}  // namespace semrec::fuse
