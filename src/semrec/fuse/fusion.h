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
//
// Evidence (Merge::kEvidence): after the paper's rule, views that
// show two objects inside one mask merge them (fuse/mask_coverage.h), an
// object's class is the vote of every mask that fell on it, a frame segment
// lying on an object of another class merges into it on a strong overlap (sigma
// > cross_class_alpha), and Finish() folds fragments into the object they touch
// or drops them. Every such decision is listed in events().
//
// Voxel (Merge::kVoxel, the default; docs/fusion.md): the evidence rule while
// streaming, and every frame's labels also vote per map voxel
// (fuse/voxel_votes.h); at the end ResolveMap() decides the objects per
// place from those votes (fuse/map_objects.h: structure only on its planes,
// objects split where apart, fragments judged by visibility) instead of the
// fragment rule.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "semrec/fuse/map_objects.h"
#include "semrec/fuse/mask_coverage.h"
#include "semrec/fuse/overlap.h"
#include "semrec/fuse/segments.h"
#include "semrec/fuse/voxel.h"
#include "semrec/fuse/voxel_votes.h"

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
  enum class Merge {
    /// The paper's rule alone.
    kPaper,
    /// The paper's rule, then multi-view evidence, class votes, cross-class
    /// merges on strong overlap and fragment cleanup (see above).
    kEvidence,
    /// Evidence while streaming, then objects decided per map voxel from
    /// every view's labels (ResolveMap).
    kVoxel,
  };
  Merge merge = Merge::kVoxel;
  EvidenceOptions evidence;
  VoxelEvidenceOptions voxel_evidence;
  MapObjectOptions map_objects;

  void Check() const;
};

/// "paper", "evidence" or "voxel"; ParseMerge throws InvalidArgument for
/// anything else.
const char* MergeName(FusionOptions::Merge merge);
FusionOptions::Merge ParseMerge(const std::string& name);

struct SceneSegment {
  uint32_t id = 0;
  /// With evidence: the class with most votes; otherwise the first segment's
  /// class (or, without gating, the class holding most points).
  uint16_t class_id = 0;
  ClassKind kind = ClassKind::kThing;
  /// Votes per class: comparison points of masks of that class that fell on
  /// this object (with evidence: every mask of every view that saw it; paper
  /// rule: the segments merged into it).
  std::map<uint16_t, uint64_t> class_votes;
  /// Stored cloud (world frame), downsampled at store_voxel_size_m.
  Cloud points;
  size_t first_seen_frame = 0;
  size_t last_seen_frame = 0;
  /// Frame segments merged into this one (including the first).
  size_t observations = 0;
  /// The frames it was seen in (sorted, unique): several segments of one
  /// frame are one sighting.
  std::vector<uint32_t> frames_seen;
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
  /// Scene objects merged by view evidence, and frame segments that merged into
  /// an object of another class on a strong overlap.
  size_t evidence_merges = 0;
  size_t cross_class_matches = 0;
  /// The evidence steps' share of `seconds` (coverage, votes, evidence merges).
  double evidence_seconds = 0.0;
  /// Whole Integrate() call, and its comparison stage alone (the overlap
  /// tests).
  double seconds = 0.0;
  double compare_seconds = 0.0;
  /// For each input frame segment, the id of the scene segment it ended in
  /// (later merges may absorb that id: SceneFusion::ResolveId gives the current
  /// one).
  std::vector<uint32_t> assigned_ids;
};

/// A decision beyond the paper's rule, for the user to audit (summary.json).
struct FusionEvent {
  enum class Kind {
    kEvidenceMerge,
    kCrossClassMatch,
    kFragmentMerge,
    kDropped
  };
  Kind kind = Kind::kEvidenceMerge;
  /// Frame it happened in (Finish(): the last frame integrated).
  size_t frame = 0;
  /// The object merged (or dropped) and the one it went into (0: none); for a
  /// cross-class match, `into` is the object a segment of class `class_id`
  /// joined.
  uint32_t id = 0;
  uint32_t into = 0;
  std::string reason;
  /// The classes of `id` (or of the segment) and `into` when they merged.
  uint16_t class_id = 0;
  uint16_t into_class_id = 0;
};
const char* FusionEventKindName(FusionEvent::Kind kind);

class SceneFusion {
 public:
  explicit SceneFusion(const FusionOptions& options = {});

  /// Fuses one frame's segments (from ExtractFrameSegments) into the scene.
  /// `observation`: what the frame saw, for the voxel evidence (Merge::kVoxel;
  /// null: only labelled voxels count as observed).
  FrameFusionStats Integrate(const std::vector<FrameSegment>& frame_segments,
                             size_t frame_index,
                             const FrameObservation* observation = nullptr);

  /// Ends the sequence: evidence merges re-checked over all pairs, fragments
  /// merged or dropped (Merge::kEvidence; nothing for the paper's rule).
  /// Returns the number of objects merged or dropped. Merge::kVoxel: evidence
  /// merges only; ResolveMap() follows.
  size_t Finish();

  /// Merge::kVoxel, after Finish(): replaces the objects by those the voxel
  /// evidence decides (`context`: up and the classes' kinds and geometry; its
  /// objects are filled here). Ids of objects that keep most of their place
  /// stay; ResolveId is not changed (volumes keep their fusion ids: see
  /// map_resolution()'s owners). Returns the resolution, also kept.
  const MapResolution& ResolveMap(MapContext context);
  /// What ResolveMap() would decide from the evidence so far, without
  /// changing the fusion (snapshots while frames still come: a user watching
  /// the scene grow sees the objects the end would give, not the wall that
  /// will give the chair back). Merge::kVoxel only.
  struct MapPreview {
    MapResolution resolution;
    std::vector<SceneSegment> segments;
  };
  MapPreview PreviewMap(MapContext context) const;
  /// PreviewMap's resolution alone (no object clouds built): what map
  /// guidance projects between segmented frames.
  MapResolution PreviewResolution(MapContext context) const;
  /// The last ResolveMap() result, or nullptr.
  const MapResolution* map_resolution() const {
    return resolution_ ? &*resolution_ : nullptr;
  }
  const VoxelEvidenceMap* voxel_evidence() const {
    return voxel_map_ ? &*voxel_map_ : nullptr;
  }

  /// Scene segments, sorted by id.
  const std::vector<SceneSegment>& segments() const { return segments_; }
  const FusionOptions& options() const { return options_; }

  /// The current id of the segment that segment `id` was merged into (itself if
  /// it was not; 0 if it was dropped).
  uint32_t ResolveId(uint32_t id) const;

  const std::vector<FusionEvent>& events() const { return events_; }
  const EvidenceGraph& evidence() const { return evidence_; }

 private:
  bool evidence_on() const {
    return options_.merge != FusionOptions::Merge::kPaper;
  }
  /// Where a frame's object masks fall on the scene's objects (structure
  /// excluded), per frame segment f and scene object s: `on[f][s]` counts f's
  /// comparison points within the correspondence distance of s (what the view
  /// shows of s, even where a duplicate of s lies on the same surface),
  /// `nearest[f][s]` those for which s is the nearest object (a mask's fringe
  /// that reaches a neighbour still counts for its own object).
  struct FrameCoverage {
    std::vector<std::vector<uint32_t>> on;
    std::vector<std::vector<uint32_t>> nearest;
  };
  /// A frame's segments at the stored and the comparison resolution.
  struct FrameClouds {
    std::vector<Cloud> store;
    std::vector<Cloud> corr;
    std::vector<Eigen::AlignedBox3f> bounds;
    std::vector<VoxelGrid> grids;  // kFast only
  };
  /// A (frame segment, scene segment) pair to compare.
  struct Candidate {
    size_t frame_segment;
    size_t scene_segment;
    double alpha;
    OverlapResult overlap;
    bool exceeds = false;
  };
  /// Integrate's steps: downsampled clouds (and the comparison counts), the
  /// map object of each map-guided segment, the pairs to compare, the matches
  /// (scene segment indices per frame segment), and applying them.
  FrameClouds PrepareClouds(const std::vector<FrameSegment>& frame_segments,
                            FrameFusionStats* stats) const;
  std::vector<std::optional<size_t>> MapObjectsOf(
      const std::vector<FrameSegment>& frame_segments) const;
  std::vector<Candidate> ListCandidates(
      const std::vector<FrameSegment>& frame_segments,
      const FrameClouds& clouds,
      const std::vector<std::optional<size_t>>& map_object,
      const FrameCoverage& coverage, std::vector<std::vector<size_t>>* matches,
      FrameFusionStats* stats) const;
  std::vector<std::vector<size_t>> MatchSegments(
      const std::vector<FrameSegment>& frame_segments,
      const FrameClouds& clouds,
      const std::vector<std::optional<size_t>>& map_object,
      const FrameCoverage& coverage, size_t frame_index,
      FrameFusionStats* stats);
  void ApplyMatches(const std::vector<FrameSegment>& frame_segments,
                    const std::vector<std::vector<size_t>>& matches,
                    const std::vector<std::optional<size_t>>& map_object,
                    size_t frame_index, FrameClouds* clouds,
                    FrameFusionStats* stats);
  /// One group of scene segments linked this frame, with the frame segments
  /// attached to it, as one segment (clouds not rebuilt).
  SceneSegment MergeGroup(size_t root, const std::vector<size_t>& group,
                          const std::vector<size_t>& attached,
                          const std::vector<FrameSegment>& frame_segments,
                          const std::vector<std::optional<size_t>>& map_object,
                          const FrameClouds& clouds, size_t frame_index,
                          FrameFusionStats* stats);
  FrameCoverage Coverage(
      const std::vector<FrameSegment>& frame_segments,
      const std::vector<Cloud>& frame_corr,
      const std::vector<Eigen::AlignedBox3f>& frame_bounds) const;
  /// Class votes (from `nearest`) and view evidence (from `on`) of one frame,
  /// before its merges.
  void RecordViewEvidence(const std::vector<FrameSegment>& frame_segments,
                          const FrameCoverage& coverage, size_t frame_index);
  /// The segment's class is `class_id`, or (with evidence) its votes give
  /// that class at least confusion_share.
  bool ConfusedWith(const SceneSegment& s, uint16_t class_id) const;
  /// Merges each group of segments_ indices into its first member (it keeps
  /// its id) and rebuilds the merged clouds; returns the number absorbed.
  size_t MergeGroups(const std::vector<std::vector<size_t>>& groups);
  /// Evidence merges over all pairs the graph says are one (classes
  /// permitting).
  size_t MergeByEvidence(size_t frame_index);
  /// Folds fragments into the object of their class they touch, or drops them.
  size_t CleanFragments();
  /// Moves `from`'s points, votes and history into `into` (clouds not rebuilt).
  void Absorb(SceneSegment* into, SceneSegment* from);
  void Rebuild(SceneSegment* s) const;
  /// ResolveMap's decision; new ids from `next_id` (advanced).
  MapPreview DecideMap(MapContext context, uint32_t* next_id) const;
  /// Its resolution step (fills `context`'s objects).
  MapResolution DecideResolution(MapContext* context, uint32_t* next_id) const;
  void UpdateClass(SceneSegment* s) const;

  FusionOptions options_;
  EvidenceGraph evidence_;
  std::vector<FusionEvent> events_;
  size_t last_frame_ = 0;
  std::vector<SceneSegment> segments_;
  uint32_t next_id_ = 1;
  /// Absorbed segment id -> the id it was merged into.
  std::map<uint32_t, uint32_t> merged_into_;
  std::optional<VoxelEvidenceMap> voxel_map_;
  std::optional<MapResolution> resolution_;
};

}  // namespace semrec::fuse
