// What `semrec run` reports about a run (report.json), as one typed struct:
// RunSequence fills it, ToJson/ParseRunReport are the only places that know
// its JSON keys, and the terminal summary, report.html, the benchmarks and
// the Python module read the struct. The diagnostic sub-documents (timing,
// gravity, fusion events, the map resolution's counts) are written as their
// producers make them and kept as JSON.
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace semrec::pipeline {

/// Seconds per processed frame, by stage.
struct StageRates {
  double read = 0.0, segment = 0.0, track = 0.0, fuse = 0.0, volumes = 0.0,
         overlay = 0.0, write = 0.0;
  /// (name, seconds) in pipeline order.
  std::vector<std::pair<std::string, double>> Named() const;
};

struct SkippedFrame {
  size_t frame = 0;
  std::string reason;
};

/// A model the run used, with the checksum of its installed file.
struct ModelRecord {
  std::string name, file, sha256;
  bool sha256_registered = false;  // from the registry, not computed
};

/// One object of the written scene.
struct ObjectRecord {
  uint32_t id = 0;
  std::string class_name;
  std::string kind;  // "object" or "structure"
  size_t vertices = 0, triangles = 0, fused_points = 0, observations = 0,
         frames_seen = 0;
  std::vector<std::pair<std::string, double>> class_votes;
  size_t first_seen_frame = 0, last_seen_frame = 0;
  std::string ply;  // relative to the output folder ("" = not written)
};

struct MapGuidanceReport {
  bool enabled = false;
  size_t full_frames = 0, partial_frames = 0, projection_frames = 0,
         disagreement_frames = 0, encoder_calls = 0, prompts_decoded = 0;
  double mean_unexplained_share = 0.0;
};

struct ObjectDetectorReport {
  std::optional<std::string> model;  // none: the detector was off
  double score_threshold = 0.0, weight = 0.0;
  bool stuff_yields = false;
  size_t detections = 0, matched_masks = 0, added_masks = 0, parts = 0,
         parts_joined = 0, frames_sharing_the_people_pass = 0;
};

/// One frame's estimated pose: how tracking went.
struct PoseFrameRecord {
  size_t frame = 0;
  bool tracked = true, keyframe = false;
  double fitness = 0.0, inlier_rmse_m = 0.0;
  size_t masked_pixels = 0;
  std::string lost_reason;  // "" when tracked
};

/// Where the camera poses came from.
struct PoseReport {
  std::string source = "file";  // "file" or "estimated"
  /// The recording's pose file, or the estimate written (poses.txt).
  std::string file;
  /// Estimated: the tracker's method and loss.
  std::string method;
  size_t keyframes = 0, lost_frames = 0;
  /// Time spent estimating them (s).
  double seconds = 0.0;
  std::vector<PoseFrameRecord> frames;  // estimated only
};

struct RunReport {
  std::string input;   // the recording, as the scene's metadata names it
  std::string labels;  // "models" or the given labels' spec
  size_t frames = 0, processed_frames = 0, segmented_frames = 0,
         resumed_frames = 0;
  std::vector<SkippedFrame> skipped_frames;
  double seconds = 0.0, frames_per_second = 0.0;
  StageRates seconds_per_frame;
  double peak_rss_mb = 0.0;
  size_t objects = 0, structure = 0;  // objects excludes structure
  /// Map voxels of things no volume meshed, written as small patches; objects
  /// with no surface to mesh, left out.
  size_t surface_patches = 0, skipped_empty_objects = 0;
  std::map<std::string, int> objects_per_class;
  size_t people = 0, tracks = 0, snapshots = 0;
  std::string options;              // the scene's option summary
  std::string config = "run.yaml";  // the effective options file
  std::string version;
  std::vector<ModelRecord> models;
  std::vector<ObjectRecord> scene;
  PoseReport poses;
  /// With the models only.
  std::optional<MapGuidanceReport> map_guidance;
  std::optional<ObjectDetectorReport> object_detector;
  /// Diagnostics: where the time went per thread and stage, the gravity
  /// estimate, fusion's merge events, the map resolution's counts.
  nlohmann::json timing = nlohmann::json::object();
  nlohmann::json gravity = nlohmann::json::object();
  nlohmann::json fusion_events = nlohmann::json::object();
  nlohmann::json map_objects = nlohmann::json::object();

  /// The gravity estimate's method ("" when unknown).
  std::string GravityMethod() const;
};

nlohmann::json ToJson(const RunReport& report);
/// Throws FormatError naming `file` when a field is missing or of the wrong
/// type.
RunReport ParseRunReport(const nlohmann::json& j,
                         const std::filesystem::path& file);
/// report.json in a run's output folder (written atomically).
void WriteRunReport(const std::filesystem::path& file, const RunReport& report);
RunReport ReadRunReport(const std::filesystem::path& file);

/// A written scene's objects (SceneWriteResult::objects_json) as records.
std::vector<ObjectRecord> ParseObjectRecords(const nlohmann::json& objects,
                                             const std::filesystem::path& file);

}  // namespace semrec::pipeline
