// `semrec eval scene <result-dir> <gt.ply>`: 3D semantic and instance quality
// of a reconstructed scene against a labelled ground-truth cloud.
#include <cstdio>
#include <map>
#include <optional>
#include <sstream>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "semrec/core/error.h"
#include "semrec/core/transform.h"
#include "semrec/eval/scene_metrics.h"
#include "semrec/io/json_file.h"
#include "semrec/io/label_set_io.h"
#include "semrec/usd/usda_reader.h"

namespace fs = std::filesystem;

namespace semrec::cli {
namespace {

struct SceneArgs {
  std::string result;
  std::string gt;
  std::string gt_classes;
  std::string class_map;
  std::string observed_in;
  int observed_stride = 1;
  bool json = false;
  bool objects = false;
  eval::SceneEvalOptions options;
};

// Predicted class name -> ground-truth id: the map file's entries (a JSON
// object of names to ground-truth names or ids), else the same name in the
// ground truth's classes; -1 when neither knows it.
std::map<std::string, int32_t> LoadClassMap(const std::string& path,
                                            const LabelSet& gt_classes) {
  std::map<std::string, int32_t> map;
  if (path.empty()) return map;
  const nlohmann::json j = io::ReadJsonFile(path);
  if (!j.is_object()) {
    throw FormatError(path,
                      "expected a JSON object {\"predicted class\": "
                      "ground-truth class name or id}");
  }
  for (const auto& [name, value] : j.items()) {
    if (name.rfind('_', 0) == 0) continue;  // "_comment" and the like
    if (value.is_number_integer()) {
      map[name] = value.get<int32_t>();
    } else if (value.is_string()) {
      const auto id = gt_classes.FindByName(value.get<std::string>());
      if (!id) {
        throw FormatError(path, fmt::format("'{}' maps to '{}', which is not "
                                            "a ground-truth class",
                                            name, value.get<std::string>()));
      }
      map[name] = *id;
    } else if (value.is_null()) {
      map[name] = -1;
    } else {
      throw FormatError(path, "'" + name + "': expected a name, an id or null");
    }
  }
  return map;
}

// 16 numbers, row-major, as a rigid transform; FormatError naming `file` and
// `what` (where in it the text is) otherwise.
Transform ParseUpright(const std::string& text, const fs::path& file,
                       const std::string& what) {
  std::istringstream in(text);
  Eigen::Matrix4d T;
  for (int k = 0; k < 16; ++k) {
    if (!(in >> T(k / 4, k % 4))) {
      throw FormatError(file, fmt::format("{} is not 16 numbers (a row-major "
                                          "4x4 transform): '{}'",
                                          what, text));
    }
  }
  if (in >> std::ws, !in.eof()) {
    throw FormatError(
        file, fmt::format("{} has more than 16 numbers: '{}'", what, text));
  }
  try {
    return Transform::FromMatrix(T, what);
  } catch (const InvalidArgument& e) {
    throw FormatError(file, e.what());
  }
}

// An upright transform and the file that gave it.
struct Upright {
  Transform T;
  fs::path file;
};

// The transform that turned the result upright (T_upright_world), so that the
// ground truth can be brought into the result's frame. Every result with a
// scene (`semrec run`, `semrec mesh`) writes it into its layers'
// customLayerData; summary.json's gravity (mesh only) is the fallback. The
// scene wins when both have it. Identity only when neither says the result
// was turned: guessing would score in the wrong frame without a word.
Transform UprightTransform(const fs::path& scene) {
  std::optional<Upright> from_scene;
  std::string gravity;  // the layers' "gravity" method, if any
  for (const fs::path& layer : {scene, scene.parent_path() / "static.usda"}) {
    if (!fs::exists(layer)) continue;
    const auto data = usd::ReadCustomLayerData(layer);
    if (const auto it = data.find("gravity"); it != data.end()) {
      gravity = it->second;
    }
    if (const auto it = data.find("T_upright_world"); it != data.end()) {
      from_scene = {
          ParseUpright(it->second, layer, "customLayerData T_upright_world"),
          layer};
      break;
    }
  }
  std::optional<Upright> from_summary;
  const fs::path summary = scene.parent_path() / "summary.json";
  if (fs::exists(summary)) {
    const nlohmann::json j = io::ReadJsonFile(summary);
    if (j.contains("gravity") && j["gravity"].is_object()) {
      const nlohmann::json& g = j["gravity"];
      if (gravity.empty() && g.contains("method") && g["method"].is_string()) {
        gravity = g["method"].get<std::string>();
      }
      if (g.contains("T_upright_world")) {
        if (!g["T_upright_world"].is_string()) {
          throw FormatError(summary,
                            "gravity.T_upright_world is not a string "
                            "of 16 numbers");
        }
        from_summary = {ParseUpright(g["T_upright_world"].get<std::string>(),
                                     summary, "gravity.T_upright_world"),
                        summary};
      }
    }
  }
  if (from_scene) {
    if (from_summary && !from_scene->T.IsApprox(from_summary->T, 1e-4)) {
      spdlog::warn("{} and {} disagree on T_upright_world; using the scene's",
                   from_scene->file.string(), from_summary->file.string());
    }
    return from_scene->T;
  }
  if (from_summary) return from_summary->T;
  if (!gravity.empty() && gravity != "none") {
    throw FormatError(
        scene, fmt::format("the result was turned upright (gravity: {}) but "
                           "neither its layers' customLayerData nor a "
                           "summary.json beside it has T_upright_world: "
                           "cannot bring the ground truth into its frame",
                           gravity));
  }
  return Transform();
}

void RunScene(const SceneArgs& args) {
  CheckUsage(args.options);
  const fs::path result = args.result;
  const fs::path scene =
      fs::is_directory(result) ? result / "scene.usda" : result;
  // The result is written upright: the ground truth goes into its frame
  // (read first: a result without its transform fails before the slow work).
  const Transform T_upright_world = UprightTransform(scene);
  eval::SceneGroundTruth gt = eval::ReadSceneGroundTruth(args.gt);
  fs::path classes_file = args.gt_classes;
  if (classes_file.empty()) {
    classes_file = fs::path(args.gt).parent_path() / "classes.json";
    if (!fs::exists(classes_file)) {
      throw UsageError(
          fmt::format("no {} beside the ground truth: give its classes with "
                      "--gt-classes FILE",
                      classes_file.string()));
    }
  }
  const LabelSet gt_classes = io::LoadLabelSet(classes_file.string());
  const auto map = LoadClassMap(args.class_map, gt_classes);
  const size_t all_points = gt.points.size();
  if (!args.observed_in.empty()) {
    io::SequenceReaderOptions reader_options;
    reader_options.stride = args.observed_stride;
    const io::SequenceReader reader =
        io::SequenceReader::Open(args.observed_in, reader_options);
    gt = eval::Subset(gt, eval::ObservedPoints(gt.points, reader));
  }
  for (auto& p : gt.points) {
    p = (T_upright_world * p.cast<double>()).cast<float>();
  }

  std::vector<eval::PredictedObject> predicted;
  std::map<std::string, size_t> unmapped;
  for (const usd::MeshPrim& m : usd::ReadScene(scene)) {
    eval::PredictedObject p;
    p.id = m.instance_id;
    p.score = static_cast<double>(m.point_count);
    p.surface = m.points;
    if (const auto it = map.find(m.label); it != map.end()) {
      p.class_id = it->second;
    } else if (const auto id = gt_classes.FindByName(m.label)) {
      p.class_id = *id;
    } else {
      ++unmapped[m.label];
    }
    predicted.push_back(std::move(p));
  }
  std::set<int32_t> things;
  for (const LabelClass& c : gt_classes.Classes()) {
    if (c.kind == ClassKind::kThing) things.insert(c.id);
  }
  const eval::SceneMetrics m =
      eval::EvaluateScene(gt, predicted, things, args.options);
  const auto name = [&](int32_t id) {
    return id >= 0 && gt_classes.Contains(static_cast<uint16_t>(id))
               ? gt_classes.Get(static_cast<uint16_t>(id)).name
               : fmt::format("({})", id);
  };
  size_t split = 0;
  for (const auto& [object, pieces] : m.pieces_per_gt_object) {
    split += pieces > 1;
  }
  if (args.json) {
    nlohmann::json classes = nlohmann::json::array();
    for (const auto& c : m.classes) {
      nlohmann::json jc = {{"id", c.id},
                           {"name", name(c.id)},
                           {"iou", c.iou},
                           {"tp", c.true_positives},
                           {"fp", c.false_positives},
                           {"fn", c.false_negatives}};
      if (c.has_instances) {
        jc["gt_objects"] = c.gt_objects;
        jc["ap25"] = c.ap25;
        jc["ap50"] = c.ap50;
      }
      classes.push_back(jc);
    }
    nlohmann::json objects = nlohmann::json::array();
    for (const auto& o : m.objects) {
      nlohmann::json shares = nlohmann::json::array();
      for (const auto& s : o.shares) {
        shares.push_back({{"predicted_id", s.predicted_id},
                          {"class", name(s.class_id)},
                          {"share", s.share}});
      }
      objects.push_back({{"id", o.id},
                         {"class", name(o.class_id)},
                         {"points", o.points},
                         {"best_iou", o.best_iou},
                         {"uncovered", o.uncovered},
                         {"shares", shares}});
    }
    nlohmann::json pieces = nlohmann::json::object();
    for (const auto& [object, n] : m.pieces_per_gt_object) {
      pieces[std::to_string(object)] = n;
    }
    const nlohmann::json j = {
        {"gt_points", m.gt_points},
        {"covered_points", m.covered_points},
        {"mean_iou", m.mean_iou},
        {"ap25", m.ap25},
        {"ap50", m.ap50},
        {"recall50", m.recall50},
        {"precision50", m.precision50},
        {"gt_objects", m.gt_objects},
        {"predicted_objects", m.predicted_objects},
        {"objects_per_gt_object", m.objects_per_gt_object},
        {"pieces_per_gt_object", pieces},
        {"unmapped_predicted_classes", unmapped},
        {"classes", classes},
        {"objects", objects}};
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  std::string text = fmt::format(
      "{} vs {}: {} ground-truth points{} ({:.1f}% within {} m of a "
      "predicted surface)\nmIoU {:.2f}  AP25 {:.2f}  AP50 {:.2f}  recall@0.5 "
      "{:.2f}  "
      "precision@0.5 {:.2f}  (percent)\n{} predicted objects for {} "
      "ground-truth objects ({:.2f} per object; {} objects in more than one "
      "piece)\n",
      scene.string(), args.gt, m.gt_points,
      args.observed_in.empty()
          ? std::string()
          : fmt::format(" seen in {} (of {})", args.observed_in, all_points),
      m.gt_points ? 100.0 * static_cast<double>(m.covered_points) /
                        static_cast<double>(m.gt_points)
                  : 0.0,
      args.options.radius_m, 100 * m.mean_iou, 100 * m.ap25, 100 * m.ap50,
      100 * m.recall50, 100 * m.precision50, m.predicted_objects, m.gt_objects,
      m.objects_per_gt_object, split);
  for (const auto& [label, count] : unmapped) {
    text += fmt::format(
        "note: {} predicted '{}' object(s) map to no ground-truth class "
        "(--class-map)\n",
        count, label);
  }
  text += fmt::format("\n{:>5}  {:<16} {:>7} {:>8} {:>7} {:>7}\n", "id",
                      "class", "IoU", "objects", "AP25", "AP50");
  for (const auto& c : m.classes) {
    text +=
        c.has_instances
            ? fmt::format("{:>5}  {:<16} {:>7.2f} {:>8} {:>7.2f} {:>7.2f}\n",
                          c.id, name(c.id), 100 * c.iou, c.gt_objects,
                          100 * c.ap25, 100 * c.ap50)
            : fmt::format("{:>5}  {:<16} {:>7.2f}\n", c.id, name(c.id),
                          100 * c.iou);
  }
  if (args.objects) {
    text += fmt::format(
        "\nwhere each ground-truth object's points went (predicted objects "
        "with >= 5%):\n{:>5}  {:<16} {:>7} {:>7} {:>9}  {}\n",
        "id", "class", "points", "IoU", "uncovered",
        "predicted id:class share");
    for (const auto& o : m.objects) {
      std::string shares;
      for (const auto& s : o.shares) {
        shares += fmt::format(" {}:{} {:.0f}%", s.predicted_id,
                              name(s.class_id), 100 * s.share);
      }
      text += fmt::format("{:>5}  {:<16} {:>7} {:>7.2f} {:>8.0f}% {}\n", o.id,
                          name(o.class_id), o.points, 100 * o.best_iou,
                          100 * o.uncovered, shares);
    }
  }
  std::printf("%s", text.c_str());
}

}  // namespace

void AddEvalScene(CLI::App* eval) {
  auto args = std::make_shared<SceneArgs>();
  CLI::App* cmd = eval->add_subcommand(
      "scene",
      "3D semantic and instance quality of a reconstruction (ScanNet-style): "
      "each ground-truth point takes the class and object of the nearest "
      "predicted surface within --radius-m; per-class IoU and mIoU over the "
      "ground-truth classes; instance AP at IoU 0.25 and 0.5 (ScanNet's "
      "definition, thing classes, confidence = fused points), recall and "
      "precision at 0.5, predicted objects per ground-truth object.");
  cmd->add_option("result", args->result,
                  "A `semrec run` or `semrec mesh` output folder, or its "
                  "scene.usda")
      ->required();
  cmd->add_option("gt", args->gt,
                  "Ground-truth PLY with per-point 'semantic' and 'instance' "
                  "(semrec synth: gt/surface_points.ply)")
      ->required();
  cmd->add_option("--gt-classes", args->gt_classes,
                  "Ground-truth label set (default: classes.json beside the "
                  "PLY); its thing classes are scored as instances");
  cmd->add_option("--class-map", args->class_map,
                  "JSON object mapping predicted class names to ground-truth "
                  "names or ids (data/class_maps/); unmapped names match by "
                  "name");
  cmd->add_flag("--objects", args->objects,
                "Also list each ground-truth object: its best IoU with a "
                "predicted object of its class and which predicted objects "
                "took its points (in --json always)");
  cmd->add_option("--observed-in", args->observed_in,
                  "Score only ground-truth points some frame of this "
                  "sequence saw (depth within 2 cm): ground truth sampled "
                  "from whole objects holds surfaces no camera saw");
  cmd->add_option("--observed-stride", args->observed_stride,
                  "Use every n-th frame for --observed-in (the stride the "
                  "reconstruction used)")
      ->capture_default_str();
  cmd->add_option("--radius-m", args->options.radius_m,
                  "Label transfer radius (m)")
      ->capture_default_str();
  cmd->add_flag("--json", args->json, "Print JSON");
  cmd->callback([args] { RunScene(*args); });
}

}  // namespace semrec::cli
