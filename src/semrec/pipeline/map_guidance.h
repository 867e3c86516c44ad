// Map-guided segmentation: per frame, decide from the projected map
// whether the frame needs full automatic mask generation, prompts only where
// the map cannot explain it, or no segmentation model at all, with a drift
// guard that forces a full frame every so often and after large camera motion.
#pragma once

#include <cstddef>
#include <optional>
#include <string>

#include "semrec/core/image.h"
#include "semrec/core/label_map.h"
#include "semrec/core/transform.h"
#include "semrec/fuse/map_projection.h"
#include "semrec/fuse/segments.h"
#include "semrec/segment/vote.h"

namespace semrec::pipeline {

struct MapGuidanceOptions {
  /// Below this share of unexplained valid-depth pixels the frame is labelled
  /// by projection alone (no encoder, no decoder).
  double projection_only_below = 0.05;
  /// A full segmentation at least every this many frames (1: always full), so
  /// errors in the map do not freeze in.
  int refresh_every = 10;
  /// ... and when the camera turned or moved this much since the last full
  /// frame.
  double refresh_angle_deg = 25.0;
  double refresh_distance_m = 0.75;
  /// Unexplained regions smaller than this (pixels) are noise: depth edges,
  /// splat gaps.
  int min_region_px = 400;
  /// Regions grow by this much so that prompts near an object's border still
  /// land on it.
  int region_margin_px = 8;
  /// Also prompt where the semantic branch disagrees with the map's class (a
  /// region of at least min_region_px): the map's errors get fixed before the
  /// next full frame, at the price of the semantic model on every guided
  /// frame (AddDisagreement).
  bool prompt_on_disagreement = false;
  /// With objects decided per voxel (merge 'voxel'), project the decision
  /// (each voxel once, with its object's class) instead of the fusion objects,
  /// which overlap where views disagreed: a furniture front fused as wall and
  /// as cabinet labelled guided frames in interleaved blobs of both.
  bool project_decided_map = true;
  void Check() const;
};

enum class FrameMode { kFull, kPartial, kProjectionOnly };
const char* FrameModeName(FrameMode mode);

/// Why a frame got its mode.
enum class GuidanceReason {
  kNoMapYet,
  kFirstFrame,
  kRefresh,
  kCameraMoved,
  kNewContent,
  kExplained,
  /// The map explained the frame, but the semantic branch disagrees with it
  /// somewhere (AddDisagreement).
  kDisagreement,
};
/// "no map yet", "first frame", "refresh", "camera moved", "new content",
/// "explained", "disagreement" (for logs).
const char* GuidanceReasonName(GuidanceReason reason);

struct GuidanceDecision {
  FrameMode mode = FrameMode::kFull;
  GuidanceReason reason = GuidanceReason::kNoMapYet;
  /// Where prompts may land (kPartial: the unexplained regions grown by the
  /// margin; kFull: all ones; kProjectionOnly: all zeros).
  Image<uint8_t> prompt_region;
  /// Share of valid-depth pixels in unexplained regions (after dropping small
  /// ones).
  double unexplained_share = 1.0;
  /// Where the fresh segmentation wins over the projection although the map
  /// explains the depth (AddDisagreement; empty: nowhere).
  Image<uint8_t> override_region;
};

/// The decision for a frame with the map projected into it (`projected`, from
/// fuse::ProjectMap), its pose, the pose of the last fully segmented frame
/// (none yet: full) and how many segmented frames ago that was. Non-zero
/// pixels of `ignore` (same size; may be null; the tracked people's id map)
/// are never unexplained: the tracker segments people and fusion leaves them
/// out.
GuidanceDecision DecideFrame(const fuse::ProjectedMap& projected,
                             const Transform& T_world_camera,
                             const std::optional<Transform>& T_world_last_full,
                             size_t frames_since_full,
                             const MapGuidanceOptions& options,
                             const LabelMap* ignore = nullptr);

/// With options.prompt_on_disagreement: adds to a kPartial or kProjectionOnly
/// decision the explained regions where `semantic` (the frame's semantic
/// branch) disagrees with the projected class (areas: bands under 5 pixels,
/// blurred borders, do not count), kept and grown as unexplained ones are; they
/// join the prompt region and the override region, and a projection-only frame
/// with such a region becomes partial (kDisagreement). Returns the share of
/// valid-depth pixels in those regions.
double AddDisagreement(const fuse::ProjectedMap& projected,
                       const LabelMap& semantic,
                       const MapGuidanceOptions& options,
                       GuidanceDecision* decision);

/// The labels fusion sees for a map-guided frame (kPartial, kProjectionOnly):
/// pixels the map explains take their object's class, one instance per map
/// object (listed in FrameLabels::map_objects); pixels of the prompt region the
/// map does not explain take `fresh` (the vote of the masks prompted there;
/// pixels in no mask keep the semantic branch's class); everything else is
/// unlabelled (0), so fusion sees nothing it cannot vouch for. `fresh` may be
/// null (projection only); a kFull decision returns `fresh` as it is. Throws
/// InvalidArgument when the sizes differ or a kFull/kPartial decision comes
/// without `fresh`.
fuse::FrameLabels ComposeFrameLabels(const fuse::ProjectedMap& projected,
                                     const GuidanceDecision& decision,
                                     const segment::VoteResult* fresh,
                                     const std::string& source);

/// Marks a map-guided frame's overlay: the prompt region's outline (yellow;
/// kPartial) and the mode in the top-left corner ("map: partial" etc.).
ColorImage RenderGuidanceOverlay(const ColorImage& overlay,
                                 const GuidanceDecision& decision);

}  // namespace semrec::pipeline
