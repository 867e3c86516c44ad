#include "semrec/pipeline/checkpoint.h"

#include <fmt/format.h>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/io/image_io.h"
#include "semrec/io/json_file.h"

namespace fs = std::filesystem;

namespace semrec::pipeline {
namespace {

constexpr int kCheckpointVersion = 1;

nlohmann::json DetectionsJson(const std::vector<track::Detection>& detections) {
  nlohmann::json out = nlohmann::json::array();
  for (const track::Detection& d : detections) {
    out.push_back({{"box", {d.box.left, d.box.top, d.box.width, d.box.height}},
                   {"score", d.score},
                   {"embedding", d.embedding}});
  }
  return out;
}

std::vector<track::Detection> DetectionsFrom(const nlohmann::json& j) {
  std::vector<track::Detection> out;
  for (const auto& d : j) {
    track::Detection det;
    const auto& b = d.at("box");
    det.box = {b.at(0).get<double>(), b.at(1).get<double>(),
               b.at(2).get<double>(), b.at(3).get<double>()};
    det.score = d.at("score").get<double>();
    det.embedding = d.at("embedding").get<std::vector<float>>();
    out.push_back(std::move(det));
  }
  return out;
}

}  // namespace

nlohmann::json RunIdentity::ToJson() const {
  return {{"version", kCheckpointVersion},
          {"sequence", sequence},
          {"layout", layout},
          {"frames", frames},
          {"config_sha256", config_sha256}};
}

CheckpointStore::CheckpointStore(fs::path dir) : dir_(std::move(dir)) {}

fs::path CheckpointStore::FramePath(size_t position,
                                    const std::string& suffix) const {
  return dir_ / "frames" / fmt::format("{:06}{}", position, suffix);
}

void CheckpointStore::Start(const RunIdentity& identity) {
  std::error_code ec;
  fs::remove_all(dir_, ec);
  fs::create_directories(dir_ / "frames", ec);
  if (ec) {
    throw IoError(dir_, "cannot create checkpoint folder: " + ec.message());
  }
  WriteTextFileAtomic(dir_ / "identity.json", identity.ToJson().dump(2) + "\n");
  Commit(0);
}

size_t CheckpointStore::Resume(const RunIdentity& identity) const {
  const fs::path identity_path = dir_ / "identity.json";
  if (!fs::is_regular_file(identity_path) ||
      !fs::is_regular_file(dir_ / "state.json")) {
    throw IoError(dir_,
                  "no checkpoint to resume from (run without --resume to "
                  "start afresh)");
  }
  const nlohmann::json saved = io::ReadJsonFile(identity_path);
  const nlohmann::json now = identity.ToJson();
  for (const auto& [key, what] :
       {std::pair<std::string, std::string>{"version", "checkpoint format"},
        {"sequence", "sequence"},
        {"layout", "sequence layout"},
        {"frames", "number of frames (stride / max-frames)"},
        {"config_sha256", "set of options (see run.yaml)"}}) {
    if (!saved.contains(key) || saved[key] != now[key]) {
      throw InvalidArgument(fmt::format(
          "cannot resume: the checkpoint in {} belongs to a run with a "
          "different {} ({} there, {} now); run with the same sequence and "
          "options, or "
          "without --resume (and --overwrite) to start afresh",
          dir_.string(), what, saved.contains(key) ? saved[key].dump() : "none",
          now[key].dump()));
    }
  }
  const nlohmann::json state = io::ReadJsonFile(dir_ / "state.json");
  try {
    return state.at("frames_done").get<size_t>();
  } catch (const nlohmann::json::exception& e) {
    throw FormatError(dir_ / "state.json",
                      std::string("no frames_done: ") + e.what());
  }
}

void CheckpointStore::Record(size_t position,
                             const CheckpointFrame& frame) const {
  nlohmann::json j = {{"position", position}};
  if (frame.skipped) j["skipped"] = *frame.skipped;
  if (frame.outputs) {
    const ModelOutputs& o = *frame.outputs;
    j["tracker_input"] = DetectionsJson(o.tracker_input);
    j["labels"] = o.labels.has_value();
    j["people"] = o.person_ids.NumPixels() > 0;
    if (!o.guidance.empty()) j["guidance"] = o.guidance;
    if (o.labels) {
      j["labels_source"] = o.labels->source;
      if (!o.labels->map_objects.empty()) {
        nlohmann::json objects = nlohmann::json::array();
        for (const auto& [instance, object] : o.labels->map_objects) {
          objects.push_back({instance, object});
        }
        j["map_objects"] = std::move(objects);
      }
      if (!o.labels->confidence.empty()) {
        nlohmann::json confidence = nlohmann::json::array();
        for (const auto& [instance, c] : o.labels->confidence) {
          confidence.push_back({instance, c});
        }
        j["confidence"] = std::move(confidence);
      }
      io::WritePng(FramePath(position, "_semantic.png"), o.labels->semantic);
      io::WritePng(FramePath(position, "_instance.png"), o.labels->instance);
    }
    if (o.person_ids.NumPixels() > 0) {
      io::WritePng(FramePath(position, "_person.png"), o.person_ids);
    }
  }
  // The JSON last: a record exists once its images do.
  WriteTextFileAtomic(FramePath(position, ".json"), j.dump() + "\n");
}

void CheckpointStore::Commit(size_t frames_done) const {
  WriteTextFileAtomic(
      dir_ / "state.json",
      nlohmann::json({{"frames_done", frames_done}}).dump(2) + "\n");
}

CheckpointFrame CheckpointStore::Load(size_t position) const {
  const fs::path path = FramePath(position, ".json");
  const nlohmann::json j = io::ReadJsonFile(path);
  CheckpointFrame frame;
  try {
    if (j.contains("skipped")) frame.skipped = j["skipped"].get<std::string>();
    if (j.contains("tracker_input")) {
      ModelOutputs o;
      o.tracker_input = DetectionsFrom(j["tracker_input"]);
      if (j.at("labels").get<bool>()) {
        o.labels = fuse::FrameLabels{
            io::ReadLabelImage(FramePath(position, "_instance.png")),
            io::ReadLabelImage(FramePath(position, "_semantic.png")),
            j.at("labels_source").get<std::string>()};
        if (j.contains("map_objects")) {
          for (const auto& pair : j["map_objects"]) {
            o.labels->map_objects[pair.at(0).get<uint16_t>()] =
                pair.at(1).get<uint32_t>();
          }
        }
        if (j.contains("confidence")) {
          for (const auto& pair : j["confidence"]) {
            o.labels->confidence[pair.at(0).get<uint16_t>()] =
                pair.at(1).get<float>();
          }
        }
      }
      if (j.contains("guidance")) o.guidance = j["guidance"].get<std::string>();
      if (j.at("people").get<bool>()) {
        o.person_ids = io::ReadLabelImage(FramePath(position, "_person.png"));
      }
      frame.outputs = std::move(o);
    }
  } catch (const nlohmann::json::exception& e) {
    throw FormatError(path,
                      std::string("damaged checkpoint record: ") + e.what());
  }
  return frame;
}

}  // namespace semrec::pipeline
