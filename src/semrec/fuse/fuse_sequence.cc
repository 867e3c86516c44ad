#include "semrec/fuse/fuse_sequence.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/core/stopwatch.h"
#include "semrec/io/ply_io.h"

namespace fs = std::filesystem;

namespace semrec::fuse {
namespace {

std::vector<std::pair<uint16_t, double>> SortedShares(
    const SceneSegment& segment) {
  uint64_t total = 0;
  for (const auto& [cls, n] : segment.class_votes) total += n;
  std::vector<std::pair<uint16_t, double>> shares;
  for (const auto& [cls, n] : segment.class_votes) {
    if (n > 0) {
      shares.emplace_back(cls,
                          static_cast<double>(n) / static_cast<double>(total));
    }
  }
  std::stable_sort(
      shares.begin(), shares.end(),
      [](const auto& a, const auto& b) { return a.second > b.second; });
  return shares;
}

std::string ClassName(const LabelSet& classes, uint16_t id) {
  return classes.Contains(id) ? classes.Get(id).name : fmt::format("#{}", id);
}

}  // namespace

nlohmann::json ClassVotesJson(const SceneSegment& segment,
                              const LabelSet& classes) {
  nlohmann::json votes = nlohmann::json::array();
  for (const auto& [cls, share] : SortedShares(segment)) {
    votes.push_back({ClassName(classes, cls), std::round(share * 1000) / 1000});
  }
  return votes;
}

std::string ClassVotesText(const SceneSegment& segment,
                           const LabelSet& classes) {
  std::string text;
  for (const auto& [cls, share] : SortedShares(segment)) {
    text += fmt::format("{}{} {:.2f}", text.empty() ? "" : ", ",
                        ClassName(classes, cls), share);
  }
  return text;
}

double ClassConfidence(const SceneSegment& segment) {
  // The object's own class, which the map need not give the most votes: a
  // chair most views called wall is a chair of little confidence, not one as
  // sure as the wall's share.
  uint64_t total = 0;
  for (const auto& [cls, n] : segment.class_votes) total += n;
  if (total == 0) return 1.0;
  const auto own = segment.class_votes.find(segment.class_id);
  return own == segment.class_votes.end()
             ? 0.0
             : static_cast<double>(own->second) / static_cast<double>(total);
}

nlohmann::json FusionEventsJson(const SceneFusion& fusion,
                                const LabelSet& classes) {
  nlohmann::json events = nlohmann::json::array();
  for (const FusionEvent& e : fusion.events()) {
    nlohmann::json event = {{"event", FusionEventKindName(e.kind)},
                            {"frame", e.frame},
                            {"id", e.id},
                            {"into", e.into},
                            {"reason", e.reason}};
    event["class"] = ClassName(classes, e.class_id);
    if (e.into != 0) event["into_class"] = ClassName(classes, e.into_class_id);
    events.push_back(std::move(event));
  }
  return events;
}

GravityEstimate EstimateSceneGravity(const SceneFusion& fusion,
                                     const LabelSet& classes,
                                     const std::vector<Transform>& cameras,
                                     const GravityOptions& options) {
  std::vector<const Cloud*> clouds;
  std::vector<bool> is_floor;
  for (const SceneSegment& s : fusion.segments()) {
    clouds.push_back(&s.points);
    is_floor.push_back(classes.Get(s.class_id).name == "floor");
  }
  return EstimateGravity(clouds, is_floor, cameras, options);
}

nlohmann::json MapResolutionJson(const SceneFusion& fusion,
                                 const LabelSet& classes) {
  const MapResolution* r = fusion.map_resolution();
  if (r == nullptr) return nullptr;
  static const char* kGeometry[] = {"none", "vertical", "floor", "ceiling"};
  nlohmann::json planes = nlohmann::json::array();
  for (const StructurePlane& p : r->planes) {
    planes.push_back({{"class", ClassName(classes, p.class_id)},
                      {"geometry", kGeometry[static_cast<int>(p.geometry)]},
                      {"normal", {p.normal.x(), p.normal.y(), p.normal.z()}},
                      {"offset_m", p.offset},
                      {"voxels", p.support}});
  }
  // Why each object was kept: how it was seen (things only).
  nlohmann::json objects = nlohmann::json::array();
  for (const MapObject& o : r->objects) {
    if (o.kind == ClassKind::kStuff) continue;
    objects.push_back({{"id", o.id},
                       {"class", ClassName(classes, o.class_id)},
                       {"voxels", o.voxels.size()},
                       {"seen_ratio", std::round(o.seen_ratio * 1000) / 1000},
                       {"max_views", o.max_views}});
  }
  return {{"objects", r->objects.size()},
          {"visibility", objects},
          {"planes", planes},
          {"voxels_moved_off_structure", r->gated_voxels},
          {"split", r->split_objects},
          {"merged_by_masks", r->merged_objects},
          {"new_from_unclaimed_voxels", r->new_objects},
          {"fragments_folded", r->fragments_folded},
          {"fragments_dropped", r->fragments_dropped},
          {"stranded_voxels_claimed", r->stranded_voxels_claimed},
          {"enclosed_voxels_claimed", r->enclosed_voxels_claimed},
          {"far_specks_moved", r->far_specks_moved},
          {"reclassed_on_fronts", r->reclassed_on_fronts},
          {"objects_from_fronts", r->objects_from_fronts}};
}

FuseSequenceResult FuseSequence(const io::SequenceReader& reader,
                                const SegmentationSource& source,
                                const SegmentExtractionOptions& extraction,
                                SceneFusion* fusion,
                                const ProgressOptions& progress_options) {
  CheckArgument(fusion != nullptr, "FuseSequence: fusion is null");
  const Stopwatch start;
  FuseSequenceResult result;
  Progress progress("fusing", reader.size(), progress_options);
  std::vector<Transform> cameras;
  for (size_t i = 0; i < reader.size(); ++i) {
    const Frame frame = reader.Read(i);
    const FrameLabels labels = source.Get(reader, i);
    const std::vector<FrameSegment> segments =
        ExtractFrameSegments(frame, labels, source.classes(), extraction);
    cameras.push_back(frame.T_world_camera);
    if (segments.empty()) {
      ++result.empty_frames;
      spdlog::debug("frame {} ({}): no segment with valid depth, skipped", i,
                    frame.depth_path.string());
    }
    std::optional<FrameObservation> observation;
    if (fusion->voxel_evidence() != nullptr) {
      observation =
          ObserveFrame(frame, labels, nullptr, extraction.pixel_stride);
    }
    result.frames.push_back(
        fusion->Integrate(segments, i, observation ? &*observation : nullptr));
    progress.Tick();
  }
  progress.Finish();
  const size_t cleaned = fusion->Finish();
  if (cleaned > 0) {
    spdlog::info(
        "end of sequence: {} objects merged or dropped (evidence, "
        "fragments)",
        cleaned);
  }
  if (fusion->voxel_evidence() != nullptr) {
    // Up decides which planes are walls and floors.
    const GravityEstimate gravity = EstimateSceneGravity(
        *fusion, source.classes(), cameras, GravityOptions{});
    fusion->ResolveMap(MakeMapContext(source.classes(), gravity.up_world));
  }
  if (result.empty_frames > 0) {
    spdlog::warn("{} of {} frames had no segment with valid depth",
                 result.empty_frames, reader.size());
  }
  result.seconds = start.Elapsed();
  return result;
}

void WriteFusionResult(const fs::path& out_dir, const SceneFusion& fusion,
                       const LabelSet& classes,
                       const FuseSequenceResult& result,
                       const std::string& input_description, bool overwrite) {
  RequireEmptyOrOverwrite(out_dir, overwrite);
  io::PlyData all;
  nlohmann::json segments = nlohmann::json::array();
  for (const SceneSegment& s : fusion.segments()) {
    const LabelClass& cls = classes.Get(s.class_id);
    const std::string file =
        fmt::format("segments/{:04}_{}.ply", s.id, cls.name);
    io::PlyData ply;
    ply.points = s.points;
    ply.colors.assign(s.points.size(), cls.color);
    io::WritePly(out_dir / file, ply);
    all.points.insert(all.points.end(), s.points.begin(), s.points.end());
    all.colors.insert(all.colors.end(), s.points.size(), cls.color);
    all.labels.insert(all.labels.end(), s.points.size(), s.id);
    const Eigen::AlignedBox3f& b = s.bounds;
    segments.push_back({{"id", s.id},
                        {"class_id", s.class_id},
                        {"class", cls.name},
                        {"points", s.points.size()},
                        {"first_seen_frame", s.first_seen_frame},
                        {"last_seen_frame", s.last_seen_frame},
                        {"observations", s.observations},
                        {"frames_seen", s.frames_seen.size()},
                        {"class_votes", ClassVotesJson(s, classes)},
                        {"bounds_min", {b.min().x(), b.min().y(), b.min().z()}},
                        {"bounds_max", {b.max().x(), b.max().y(), b.max().z()}},
                        {"file", file}});
  }
  io::WritePly(out_dir / "fused.ply", all);
  nlohmann::json frames = nlohmann::json::array();
  for (const FrameFusionStats& f : result.frames) {
    frames.push_back(
        {{"frame", f.frame_index},
         {"frame_segments", f.frame_segments},
         {"scene_segments_before", f.scene_segments_before},
         {"frame_points", f.frame_points},
         {"scene_points", f.scene_points},
         {"compared_pairs", f.compared_pairs},
         {"distance_computations_ungated", f.distance_computations_ungated},
         {"distance_computations_gated", f.distance_computations_gated},
         {"distance_computations_done", f.distance_computations_done},
         {"merged", f.merged_frame_segments},
         {"new", f.new_segments},
         {"evidence_merges", f.evidence_merges},
         {"cross_class_matches", f.cross_class_matches},
         {"evidence_seconds", f.evidence_seconds},
         {"seconds", f.seconds}});
  }
  const FusionOptions& o = fusion.options();
  const nlohmann::json summary = {
      {"input", input_description},
      {"options",
       {{"corr_voxel_size_m", o.corr_voxel_size_m},
        {"store_voxel_size_m", o.store_voxel_size_m},
        {"max_corr_dist_m", o.max_corr_dist_m},
        {"alpha", o.alpha},
        {"label_gating", o.label_gating},
        {"merge", MergeName(o.merge)},
        {"method",
         o.method == FusionOptions::Method::kFast ? "fast" : "brute_force"}}},
      {"segments", segments},
      {"frames", frames},
      {"events", FusionEventsJson(fusion, classes)},
      {"map_objects", MapResolutionJson(fusion, classes)},
      {"empty_frames", result.empty_frames},
      {"seconds", result.seconds}};
  WriteTextFileAtomic(out_dir / "summary.json", summary.dump(2) + "\n");
}

}  // namespace semrec::fuse
