// Running fusion over a whole sequence and writing its result (the `semrec
// fuse` command).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "semrec/core/progress.h"
#include "semrec/fuse/fusion.h"
#include "semrec/fuse/gravity.h"
#include "semrec/fuse/segments.h"
#include "semrec/io/sequence_reader.h"

namespace semrec::fuse {

struct FuseSequenceResult {
  std::vector<FrameFusionStats> frames;
  /// Frames that had no valid depth or no segment (skipped, counted here).
  size_t empty_frames = 0;
  double seconds = 0.0;
};

/// The class votes as [[class name, share], ...], largest first, and as text
/// ("chair 0.72, table 0.28").
nlohmann::json ClassVotesJson(const SceneSegment& segment,
                              const LabelSet& classes);
std::string ClassVotesText(const SceneSegment& segment,
                           const LabelSet& classes);
/// The share of the object's class among its votes (1 without votes; 0 when
/// none is for its class).
double ClassConfidence(const SceneSegment& segment);
/// fusion.events() for summary.json.
/// Up and the floor from the scene's objects (those of a class named
/// "floor" marked as floor) and the cameras (fuse/gravity.h).
GravityEstimate EstimateSceneGravity(const SceneFusion& fusion,
                                     const LabelSet& classes,
                                     const std::vector<Transform>& cameras,
                                     const GravityOptions& options);

nlohmann::json FusionEventsJson(const SceneFusion& fusion,
                                const LabelSet& classes);

/// What ResolveMap decided (merge "voxel"): each object's visibility (id,
/// class, voxels, seen ratio, most views labelling one voxel), the structure
/// planes (class, geometry, normal, offset, voxels on it) and the counts of
/// voxels moved off structure, objects split, merged, made and fragments
/// folded or dropped;
/// null before ResolveMap or with another merge rule.
nlohmann::json MapResolutionJson(const SceneFusion& fusion,
                                 const LabelSet& classes);

/// Reads every frame of `reader`, extracts its segments with `source`, fuses
/// them, then calls fusion->Finish().
FuseSequenceResult FuseSequence(const io::SequenceReader& reader,
                                const SegmentationSource& source,
                                const SegmentExtractionOptions& extraction,
                                SceneFusion* fusion,
                                const ProgressOptions& progress = {});

/// Writes `out_dir`/segments/<id>_<class>.ply (one cloud per fused segment,
/// class colour), `out_dir`/fused.ply (all segments, `label` = segment id) and
/// `out_dir`/summary.json (options, per-segment class/points/frames, per-frame
/// statistics, timings). Refuses a non-empty folder unless `overwrite`.
void WriteFusionResult(const std::filesystem::path& out_dir,
                       const SceneFusion& fusion, const LabelSet& classes,
                       const FuseSequenceResult& result,
                       const std::string& input_description, bool overwrite);

}  // namespace semrec::fuse
