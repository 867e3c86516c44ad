// What the map already knows, seen from a new frame (for map-guided
// segmentation): the fused objects' stored clouds are splatted into the frame
// with a z-buffer, giving per pixel the nearest object, its class and its
// depth. A pixel is *explained* when an object covers it and the measured depth
// agrees with the object's depth; it *contradicts* the map when the camera sees
// farther than the object (the object moved or was removed). Everything else
// with valid depth is unexplained: new objects, new views, occluders in front
// of the map.
#pragma once

#include <cstdint>
#include <vector>

#include "semrec/core/camera.h"
#include "semrec/core/image.h"
#include "semrec/core/label_map.h"
#include "semrec/core/transform.h"
#include "semrec/fuse/fusion.h"

namespace semrec::fuse {

struct MapProjectionOptions {
  /// Each stored point covers a square of this half-size around it: half the
  /// map's 5 cm store grid tiles a surface seen face on without spilling far
  /// over its silhouette.
  float splat_radius_m = 0.025f;
  /// Splats never exceed this many pixels in radius (close points would flood
  /// the frame).
  int max_splat_px = 12;
  /// Points nearer than this to the camera are ignored.
  float min_depth_m = 0.1f;
  /// Measured and projected depth agree within tolerance_m + tolerance_ratio *
  /// depth (depth noise grows with distance; the map's surfaces are 5 cm
  /// voxels).
  float depth_tolerance_m = 0.05f;
  float depth_tolerance_ratio = 0.03f;
  /// Two objects whose depths explain a pixel within this share of the
  /// tolerance of each other are one surface to the camera (e.g. a wall fused
  /// once as wall, once as cabinet): the pixel goes to the object that
  /// explains more pixels within `ambiguity_window_px` of it, not to
  /// whichever noise favours. A book a few centimetres above a table stays
  /// the book.
  float ambiguity_ratio = 0.2f;
  int ambiguity_window_px = 8;
  void Check() const;
};

struct ProjectedMap {
  /// Per pixel the map object that explains the measured depth (explained
  /// pixels: of the objects projecting there, the one whose depth is closest
  /// to the measurement), else the nearest one projecting there
  /// (SceneSegment::id; 0: none), and its class (0: none).
  Image<uint32_t> object_id;
  LabelMap class_id;
  /// Depth of that object's surface (m; 0: none).
  DepthImage depth_m;
  /// Per pixel: kExplained (an object projects there at the measured depth,
  /// within the tolerance; a nearer object's splat spilling over a silhouette
  /// does not hide it), kContradicted (the camera sees past the nearest object
  /// and no object lies at the measured depth, inside the nearest object's
  /// silhouette: on its one-pixel rim the splats' spill is no evidence),
  /// kNoDepth (no valid measured depth), else kUnexplained.
  Image<uint8_t> state;
  size_t valid_depth_pixels = 0;
  size_t explained_pixels = 0;
  size_t contradicted_pixels = 0;

  static constexpr uint8_t kUnexplained = 0;
  static constexpr uint8_t kExplained = 1;
  static constexpr uint8_t kContradicted = 2;
  static constexpr uint8_t kNoDepth = 3;
  /// Share of the valid-depth pixels the map does not explain (1 without valid
  /// depth).
  double UnexplainedShare() const;
};

/// Projects `objects` (world frame) into the frame with `intrinsics`,
/// `T_world_camera` and measured `depth_m` (0 = invalid; its size must match
/// the intrinsics). Throws InvalidArgument for inconsistent sizes or options.
ProjectedMap ProjectMap(const std::vector<SceneSegment>& objects,
                        const CameraIntrinsics& intrinsics,
                        const Transform& T_world_camera,
                        const DepthImage& depth_m,
                        const MapProjectionOptions& options = {});

/// The map as guidance projects it when objects are decided per voxel (merge
/// 'voxel'). The fusion objects overlap where views disagreed (a furniture
/// front fused once as wall, once as cabinet) and projected side by side they
/// interleave in blobs; `resolution` gives each voxel one owner. Each decided
/// voxel is splatted once, at its centroid, under the fusion object holding
/// its surface (VoxelOwner::source: the id fusion attaches projected pixels
/// to), with its decided object's class; stored points in no decided voxel
/// (dropped fragments, surfaces only projection added) stay as they are. One
/// segment per (fusion object, class), ordered by both.
std::vector<SceneSegment> DecidedMapForProjection(
    const std::vector<SceneSegment>& segments, const MapResolution& resolution,
    const VoxelEvidenceMap& evidence);

}  // namespace semrec::fuse
