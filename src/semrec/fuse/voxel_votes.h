// Class evidence per map voxel: every view that sees a place votes on it.
//
// A segment's class is decided per view by a 2D model whose mistakes are
// correlated with place (the lower part of a chair called floor, a table
// against the wall called wall). The object a mislabelled segment joined must
// not keep those points forever, so the map keeps, per stored voxel (the 5 cm
// map), a class histogram and the objects its points were assigned to, from
// every frame that labelled it, and how many frames observed it at all
// (labelled or not). The final objects are decided from these at the end
// (fuse/map_objects.h).
//
// Each view casts one vote per voxel, split over the classes its pixels in
// that voxel carry (a voxel on a mask border is half chair, half wall in that
// view), weighted by distance: beyond `full_weight_distance_m` a pixel covers
// more of the surface and a 2D model's boundaries blur (it sees the frame at
// ~512 px), so far views count less. Counting views rather than pixels keeps a
// single close-up view from outvoting every other view of the place. Each
// pixel's part of the vote is scaled by its instance's confidence
// (FrameLabels::confidence: the vote's mass on the mask's winning class, with
// the object detector's evidence): a mask the segmenter was unsure of (a
// chair 55% wall) casts less than one that all pixels and the detector agree
// on (SemanticFusion and Kimera-Semantics weigh by the model's probability
// per pixel; the vote's per-mask probability is what semrec's labels carry).
#pragma once

#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "semrec/fuse/segments.h"
#include "semrec/fuse/voxel.h"

namespace semrec::fuse {

struct VoxelEvidenceOptions {
  /// Views closer than this vote with weight 1; farther, weight
  /// full_weight_distance_m / distance.
  double full_weight_distance_m = 2.0;
  /// A view counts as showing class c in a voxel (for visibility, see
  /// map_objects.h) when at least this share of its pixels there carry c.
  double view_class_share = 0.5;
  /// Keep each frame's labels where it had no depth (FarView) and let them
  /// vote on the voxels beyond the frame's reach (FarVotes).
  bool far_views = true;

  void Check() const;
};

struct ClassEvidence {
  uint16_t class_id = 0;
  /// Views in which the class held view_class_share of the voxel's pixels.
  uint16_t views = 0;
  /// Summed distance- and confidence-weighted view shares.
  float weight = 0.0f;
};

/// The entry of `class_id` in `classes`, added (no weight, no views) when
/// missing.
ClassEvidence* FindOrAddClass(std::vector<ClassEvidence>* classes,
                              uint16_t class_id);

struct ObjectVote {
  /// Fusion object id at the time of the view (resolve it through merges).
  uint32_t id = 0;
  /// Summed view shares (1 per view that put all its pixels here into it).
  float views = 0.0f;
};

struct VoxelEvidence {
  /// Centroid of the labelled points that fell into the voxel.
  Eigen::Vector3d point_sum = Eigen::Vector3d::Zero();
  uint32_t points = 0;
  /// Frames that observed the voxel (a pixel with depth in it, labelled or
  /// not).
  uint32_t views = 0;
  /// Sum over the views that labelled it of the unit vector from it towards
  /// the camera (zero without camera positions): the side a surface was seen
  /// from; an interior wall's two faces, 10 cm apart, face opposite ways.
  Eigen::Vector3f towards_camera_sum = Eigen::Vector3f::Zero();
  /// Sum over the labelled points with a surface normal (FrameSegment::
  /// normals_world) of n n^T: the surface's orientation whichever side it was
  /// seen from (the two faces of a board cancel in a sum of normals, not here).
  Eigen::Matrix3f normal_scatter = Eigen::Matrix3f::Zero();
  std::vector<ClassEvidence> classes;
  std::vector<ObjectVote> objects;
  /// Per view that put object pixels here, the object mask (MaskId) holding
  /// most of them, in frame order: which parts views saw inside one mask
  /// (structure masks are not kept).
  std::vector<uint64_t> masks;

  Eigen::Vector3f Centroid() const {
    if (points == 0) return Eigen::Vector3f::Zero();
    return (point_sum / static_cast<double>(points)).cast<float>();
  }
  const ClassEvidence* Find(uint16_t class_id) const;
  /// The surface's normal axis (unit, either sign) when at least
  /// `min_points` points' normals agree on one: its share of the scatter (the
  /// largest eigenvalue over the trace, the number of normals) at least
  /// `min_share`; a corner of two surfaces, a rough or barely measured one
  /// has none (false).
  bool SurfaceAxis(float min_share, float min_points,
                   Eigen::Vector3f* axis) const;
};

class VoxelEvidenceMap {
 public:
  VoxelEvidenceMap(double voxel_size_m, const VoxelEvidenceOptions& options);

  /// Adds one frame: `segments` with the object each ended in (`object_ids`,
  /// parallel; 0: not fused) cast their votes, `observation` marks what the
  /// frame saw (may be null: only the labelled voxels count as observed).
  /// Segments with `map_object` set are the map's own projection: no vote.
  void AddFrame(const std::vector<FrameSegment>& segments,
                const std::vector<uint32_t>& object_ids,
                const FrameObservation* observation, size_t frame_index);

  const std::unordered_map<uint64_t, VoxelEvidence>& voxels() const {
    return voxels_;
  }
  double voxel_size_m() const { return voxel_size_m_; }
  float inv_voxel_size() const { return inv_voxel_; }
  /// Voxels with class evidence.
  size_t labelled_voxels() const;

  /// The far views' class votes, per voxel key. A depth sensor stops at 4-5
  /// m; a view of a sofa across the room still shows its class, and in a
  /// walk-through most views of a far object are of this kind. Each far view
  /// (FarView, kept by AddFrame) votes on the labelled voxels it shows: each
  /// grid cell with a label and no depth, inside a region of one class (its
  /// 4-neighbours alike: borders blur), on the voxels of the nearest surface
  /// along it (the voxels' centroids splatted at their size into the grid;
  /// those within two voxels of the nearest), when that surface lies beyond
  /// the view's reach (max_ranged_depth_m: the sensor could not range it, so
  /// the missing depth says nothing against it). One vote per view and
  /// voxel, split over its cells' classes and scaled by their confidence but
  /// not by distance (that damps the blurred borders of ranged views, which
  /// the interior rule leaves out here). Each far view counts as a view
  /// that could see the voxel (FarEvidence::views), and as a view of the
  /// classes holding view_class_share of its cells there (ClassEvidence::
  /// views; the map resolver uses both only for classes no ranged view gave,
  /// MapResolver::Visibility). Computed from the voxels as they are now, so a
  /// far view taken before a voxel was ranged still votes on it.
  struct FarEvidence {
    std::vector<ClassEvidence> classes;
    /// Far views that voted on the voxel (whatever the class): they could
    /// see it, as `VoxelEvidence::views` counts the ranged ones.
    uint32_t views = 0;
  };
  std::unordered_map<uint64_t, FarEvidence> FarVotes() const;
  /// The class of each object mask (MaskId) in VoxelEvidence::masks.
  uint16_t MaskClass(uint64_t mask) const {
    const auto it = mask_classes_.find(mask);
    return it == mask_classes_.end() ? uint16_t{0} : it->second;
  }
  size_t far_view_count() const { return far_views_.size(); }

 private:
  double voxel_size_m_;
  float inv_voxel_;
  VoxelEvidenceOptions options_;
  std::unordered_map<uint64_t, VoxelEvidence> voxels_;
  std::vector<FarView> far_views_;  // those with labelled cells
  std::unordered_map<uint64_t, uint16_t> mask_classes_;
};

/// A view's mask: frame index and the mask's label in that frame.
inline uint64_t MaskId(size_t frame, uint16_t label) {
  return (static_cast<uint64_t>(frame) << 16) | label;
}
inline size_t MaskFrame(uint64_t mask) { return mask >> 16; }

}  // namespace semrec::fuse
