// Map-guided segmentation (issue 19): per frame, decide from the projected map
// whether the frame needs full automatic mask generation, prompts only where
// the map cannot explain it, or no segmentation model at all, with a drift
// guard that forces a full frame every so often and after large camera motion.
#pragma once

#include <cstddef>
#include <optional>
#include <string>

#include "semrec/core/image.h"
#include "semrec/core/transform.h"
#include "semrec/fuse/map_projection.h"

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
  void Check() const;
};

enum class FrameMode { kFull, kPartial, kProjectionOnly };
const char* FrameModeName(FrameMode mode);

struct GuidanceDecision {
  FrameMode mode = FrameMode::kFull;
  /// Why (for logs and report.json): "first frame", "refresh", "camera moved",
  /// "new content", "explained".
  std::string reason;
  /// Where prompts may land (kPartial: the unexplained regions grown by the
  /// margin; kFull: all ones; kProjectionOnly: all zeros).
  Image<uint8_t> prompt_region;
  /// Share of valid-depth pixels in unexplained regions (after dropping small
  /// ones).
  double unexplained_share = 1.0;
};

/// The decision for a frame with the map projected into it (`projected`, from
/// fuse::ProjectMap), its pose, the pose of the last fully segmented frame
/// (none yet: full) and how many frames ago that was.
GuidanceDecision DecideFrame(const fuse::ProjectedMap& projected,
                             const Transform& T_world_camera,
                             const std::optional<Transform>& T_world_last_full,
                             size_t frames_since_full,
                             const MapGuidanceOptions& options);

}  // namespace semrec::pipeline
