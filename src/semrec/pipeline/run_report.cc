#include "semrec/pipeline/run_report.h"

#include <fmt/format.h>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/io/json_file.h"

namespace fs = std::filesystem;

namespace semrec::pipeline {
namespace {

// Reads typed fields of one JSON object; a missing or mistyped field is a
// FormatError naming the file and the field.
class Fields {
 public:
  Fields(const nlohmann::json& j, const fs::path& file, std::string where)
      : j_(j), file_(file), where_(std::move(where)) {
    if (!j_.is_object()) Fail("", "an object");
  }
  template <typename T>
  T Get(const char* key) const {
    if (!j_.contains(key)) Fail(key, "present");
    try {
      return j_.at(key).get<T>();
    } catch (const nlohmann::json::exception&) {
      Fail(key, "of the right type");
    }
  }
  const nlohmann::json& At(const char* key) const {
    if (!j_.contains(key)) Fail(key, "present");
    return j_.at(key);
  }
  const nlohmann::json& ObjectOrEmpty(const char* key) const {
    static const nlohmann::json kEmpty = nlohmann::json::object();
    return j_.contains(key) ? j_.at(key) : kEmpty;
  }
  bool Has(const char* key) const { return j_.contains(key); }

 private:
  [[noreturn]] void Fail(const std::string& key, const char* what) const {
    const std::string field = where_ + (key.empty() ? "" : "." + key);
    throw FormatError(file_,
                      fmt::format("run report: {} must be {}",
                                  field.empty() ? "the report" : field, what));
  }
  const nlohmann::json& j_;
  const fs::path& file_;
  std::string where_;
};

// Each item of the array `j` (named `name` in messages) through
// parse(item, file, index).
template <typename Parse>
auto ParseArray(const nlohmann::json& j, const char* name, const fs::path& file,
                Parse parse) {
  if (!j.is_array()) {
    throw FormatError(file,
                      fmt::format("run report: {} must be an array", name));
  }
  std::vector<decltype(parse(j, file, size_t{0}))> out;
  for (size_t i = 0; i < j.size(); ++i) out.push_back(parse(j[i], file, i));
  return out;
}

SkippedFrame ParseSkippedFrame(const nlohmann::json& j, const fs::path& file,
                               size_t index) {
  const Fields s(j, file, fmt::format("skipped_frames[{}]", index));
  return {s.Get<size_t>("frame"), s.Get<std::string>("reason")};
}

nlohmann::json ToJson(const StageRates& s) {
  nlohmann::json out = nlohmann::json::object();
  for (const auto& [name, seconds] : s.Named()) out[name] = seconds;
  return out;
}

StageRates ParseStageRates(const nlohmann::json& j, const fs::path& file) {
  const Fields f(j, file, "seconds_per_frame");
  StageRates s;
  s.read = f.Get<double>("read");
  s.segment = f.Get<double>("segment");
  s.track = f.Get<double>("track");
  s.fuse = f.Get<double>("fuse");
  s.volumes = f.Get<double>("volumes");
  s.overlay = f.Get<double>("overlay");
  s.write = f.Get<double>("write");
  return s;
}

nlohmann::json ToJson(const ObjectRecord& o) {
  nlohmann::json votes = nlohmann::json::array();
  for (const auto& [name, share] : o.class_votes)
    votes.push_back({name, share});
  return {{"id", o.id},
          {"class", o.class_name},
          {"kind", o.kind},
          {"vertices", o.vertices},
          {"triangles", o.triangles},
          {"fused_points", o.fused_points},
          {"observations", o.observations},
          {"frames_seen", o.frames_seen},
          {"class_votes", votes},
          {"first_seen_frame", o.first_seen_frame},
          {"last_seen_frame", o.last_seen_frame},
          {"ply", o.ply}};
}

ObjectRecord ParseObjectRecord(const nlohmann::json& j, const fs::path& file,
                               size_t index) {
  const Fields f(j, file, fmt::format("scene[{}]", index));
  ObjectRecord o;
  o.id = f.Get<uint32_t>("id");
  o.class_name = f.Get<std::string>("class");
  o.kind = f.Get<std::string>("kind");
  o.vertices = f.Get<size_t>("vertices");
  o.triangles = f.Get<size_t>("triangles");
  o.fused_points = f.Get<size_t>("fused_points");
  o.observations = f.Get<size_t>("observations");
  o.frames_seen = f.Get<size_t>("frames_seen");
  o.class_votes =
      f.Get<std::vector<std::pair<std::string, double>>>("class_votes");
  o.first_seen_frame = f.Get<size_t>("first_seen_frame");
  o.last_seen_frame = f.Get<size_t>("last_seen_frame");
  o.ply = f.Get<std::string>("ply");
  return o;
}

nlohmann::json ToJson(const MapGuidanceReport& g) {
  return {{"enabled", g.enabled},
          {"full_frames", g.full_frames},
          {"partial_frames", g.partial_frames},
          {"projection_frames", g.projection_frames},
          {"disagreement_frames", g.disagreement_frames},
          {"encoder_calls", g.encoder_calls},
          {"prompts_decoded", g.prompts_decoded},
          {"mean_unexplained_share", g.mean_unexplained_share}};
}

MapGuidanceReport ParseMapGuidance(const nlohmann::json& j,
                                   const fs::path& file) {
  const Fields f(j, file, "map_guidance");
  MapGuidanceReport g;
  g.enabled = f.Get<bool>("enabled");
  g.full_frames = f.Get<size_t>("full_frames");
  g.partial_frames = f.Get<size_t>("partial_frames");
  g.projection_frames = f.Get<size_t>("projection_frames");
  g.disagreement_frames = f.Get<size_t>("disagreement_frames");
  g.encoder_calls = f.Get<size_t>("encoder_calls");
  g.prompts_decoded = f.Get<size_t>("prompts_decoded");
  g.mean_unexplained_share = f.Get<double>("mean_unexplained_share");
  return g;
}

nlohmann::json ToJson(const ObjectDetectorReport& d) {
  return {{"model", d.model ? nlohmann::json(*d.model) : nlohmann::json()},
          {"score_threshold", d.score_threshold},
          {"weight", d.weight},
          {"stuff_yields", d.stuff_yields},
          {"detections", d.detections},
          {"matched_masks", d.matched_masks},
          {"added_masks", d.added_masks},
          {"parts", d.parts},
          {"parts_joined", d.parts_joined},
          {"frames_sharing_the_people_pass", d.frames_sharing_the_people_pass}};
}

ObjectDetectorReport ParseObjectDetector(const nlohmann::json& j,
                                         const fs::path& file) {
  const Fields f(j, file, "object_detector");
  ObjectDetectorReport d;
  if (!f.At("model").is_null()) d.model = f.Get<std::string>("model");
  d.score_threshold = f.Get<double>("score_threshold");
  d.weight = f.Get<double>("weight");
  d.stuff_yields = f.Get<bool>("stuff_yields");
  d.detections = f.Get<size_t>("detections");
  d.matched_masks = f.Get<size_t>("matched_masks");
  d.added_masks = f.Get<size_t>("added_masks");
  d.parts = f.Get<size_t>("parts");
  d.parts_joined = f.Get<size_t>("parts_joined");
  d.frames_sharing_the_people_pass =
      f.Get<size_t>("frames_sharing_the_people_pass");
  return d;
}

nlohmann::json ToJson(const ModelRecord& m) {
  return {{"name", m.name},
          {"file", m.file},
          {"sha256", m.sha256},
          {"sha256_registered", m.sha256_registered}};
}

ModelRecord ParseModel(const nlohmann::json& j, const fs::path& file,
                       size_t index) {
  const Fields f(j, file, fmt::format("models[{}]", index));
  return {f.Get<std::string>("name"), f.Get<std::string>("file"),
          f.Get<std::string>("sha256"), f.Get<bool>("sha256_registered")};
}

nlohmann::json ToJson(const PoseReport& p) {
  nlohmann::json frames = nlohmann::json::array();
  for (const PoseFrameRecord& f : p.frames) {
    frames.push_back({{"frame", f.frame},
                      {"tracked", f.tracked},
                      {"keyframe", f.keyframe},
                      {"fitness", f.fitness},
                      {"inlier_rmse_m", f.inlier_rmse_m},
                      {"masked_pixels", f.masked_pixels},
                      {"lost_reason", f.lost_reason}});
  }
  return {{"source", p.source},
          {"file", p.file},
          {"method", p.method},
          {"keyframes", p.keyframes},
          {"lost_frames", p.lost_frames},
          {"seconds", p.seconds},
          {"frames", frames}};
}

PoseFrameRecord ParsePoseFrame(const nlohmann::json& j, const fs::path& file,
                               size_t index) {
  const Fields f(j, file, fmt::format("poses.frames[{}]", index));
  PoseFrameRecord r;
  r.frame = f.Get<size_t>("frame");
  r.tracked = f.Get<bool>("tracked");
  r.keyframe = f.Get<bool>("keyframe");
  r.fitness = f.Get<double>("fitness");
  r.inlier_rmse_m = f.Get<double>("inlier_rmse_m");
  r.masked_pixels = f.Get<size_t>("masked_pixels");
  r.lost_reason = f.Get<std::string>("lost_reason");
  return r;
}

PoseReport ParsePoses(const nlohmann::json& j, const fs::path& file) {
  const Fields f(j, file, "poses");
  PoseReport p;
  p.source = f.Get<std::string>("source");
  p.file = f.Get<std::string>("file");
  p.method = f.Get<std::string>("method");
  p.keyframes = f.Get<size_t>("keyframes");
  p.lost_frames = f.Get<size_t>("lost_frames");
  p.seconds = f.Get<double>("seconds");
  p.frames = ParseArray(f.At("frames"), "poses.frames", file, ParsePoseFrame);
  return p;
}

}  // namespace

std::vector<std::pair<std::string, double>> StageRates::Named() const {
  return {{"read", read},  {"segment", segment}, {"track", track},
          {"fuse", fuse},  {"volumes", volumes}, {"overlay", overlay},
          {"write", write}};
}

std::string RunReport::GravityMethod() const {
  return gravity.is_object() && gravity.contains("method") &&
                 gravity.at("method").is_string()
             ? gravity.at("method").get<std::string>()
             : "";
}

nlohmann::json ToJson(const RunReport& r) {
  nlohmann::json skipped = nlohmann::json::array();
  for (const SkippedFrame& s : r.skipped_frames) {
    skipped.push_back({{"frame", s.frame}, {"reason", s.reason}});
  }
  nlohmann::json models = nlohmann::json::array();
  for (const ModelRecord& m : r.models) models.push_back(ToJson(m));
  nlohmann::json scene = nlohmann::json::array();
  for (const ObjectRecord& o : r.scene) scene.push_back(ToJson(o));
  nlohmann::json out = {{"input", r.input},
                        {"labels", r.labels},
                        {"frames", r.frames},
                        {"processed_frames", r.processed_frames},
                        {"segmented_frames", r.segmented_frames},
                        {"resumed_frames", r.resumed_frames},
                        {"skipped_frames", skipped},
                        {"seconds", r.seconds},
                        {"frames_per_second", r.frames_per_second},
                        {"seconds_per_frame", ToJson(r.seconds_per_frame)},
                        {"timing", r.timing},
                        {"peak_rss_mb", r.peak_rss_mb},
                        {"objects", r.objects},
                        {"structure", r.structure},
                        {"surface_patches", r.surface_patches},
                        {"skipped_empty_objects", r.skipped_empty_objects},
                        {"objects_per_class", r.objects_per_class},
                        {"people", r.people},
                        {"tracks", r.tracks},
                        {"snapshots", r.snapshots},
                        {"gravity", r.gravity},
                        {"options", r.options},
                        {"config", r.config},
                        {"version", r.version},
                        {"models", models},
                        {"scene", scene},
                        {"poses", ToJson(r.poses)},
                        {"fusion_events", r.fusion_events},
                        {"map_objects", r.map_objects}};
  if (r.map_guidance) out["map_guidance"] = ToJson(*r.map_guidance);
  if (r.object_detector) out["object_detector"] = ToJson(*r.object_detector);
  return out;
}

std::vector<ObjectRecord> ParseObjectRecords(const nlohmann::json& objects,
                                             const fs::path& file) {
  return ParseArray(objects, "scene", file, ParseObjectRecord);
}

RunReport ParseRunReport(const nlohmann::json& j, const fs::path& file) {
  const Fields f(j, file, "");
  RunReport r;
  r.input = f.Get<std::string>("input");
  r.labels = f.Get<std::string>("labels");
  r.frames = f.Get<size_t>("frames");
  r.processed_frames = f.Get<size_t>("processed_frames");
  r.segmented_frames = f.Get<size_t>("segmented_frames");
  r.resumed_frames = f.Get<size_t>("resumed_frames");
  r.skipped_frames = ParseArray(f.At("skipped_frames"), "skipped_frames", file,
                                ParseSkippedFrame);
  r.seconds = f.Get<double>("seconds");
  r.frames_per_second = f.Get<double>("frames_per_second");
  r.seconds_per_frame = ParseStageRates(f.At("seconds_per_frame"), file);
  r.peak_rss_mb = f.Get<double>("peak_rss_mb");
  r.objects = f.Get<size_t>("objects");
  r.structure = f.Get<size_t>("structure");
  r.surface_patches = f.Get<size_t>("surface_patches");
  r.skipped_empty_objects = f.Get<size_t>("skipped_empty_objects");
  r.objects_per_class = f.Get<std::map<std::string, int>>("objects_per_class");
  r.people = f.Get<size_t>("people");
  r.tracks = f.Get<size_t>("tracks");
  r.snapshots = f.Get<size_t>("snapshots");
  r.options = f.Get<std::string>("options");
  r.config = f.Get<std::string>("config");
  r.version = f.Get<std::string>("version");
  r.models = ParseArray(f.At("models"), "models", file, ParseModel);
  r.scene = ParseObjectRecords(f.At("scene"), file);
  // Reports written before pose estimation have no "poses".
  if (f.Has("poses")) r.poses = ParsePoses(f.At("poses"), file);
  if (f.Has("map_guidance")) {
    r.map_guidance = ParseMapGuidance(f.At("map_guidance"), file);
  }
  if (f.Has("object_detector")) {
    r.object_detector = ParseObjectDetector(f.At("object_detector"), file);
  }
  r.timing = f.ObjectOrEmpty("timing");
  r.gravity = f.ObjectOrEmpty("gravity");
  r.fusion_events = f.ObjectOrEmpty("fusion_events");
  r.map_objects = f.ObjectOrEmpty("map_objects");
  return r;
}

void WriteRunReport(const fs::path& file, const RunReport& report) {
  WriteTextFileAtomic(file, ToJson(report).dump(2) + "\n");
}

RunReport ReadRunReport(const fs::path& file) {
  return ParseRunReport(io::ReadJsonFile(file), file);
}

}  // namespace semrec::pipeline
