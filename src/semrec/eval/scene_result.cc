#include "semrec/eval/scene_result.h"

#include <set>
#include <sstream>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "semrec/core/error.h"
#include "semrec/eval/trajectory.h"
#include "semrec/io/image_io.h"
#include "semrec/io/json_file.h"
#include "semrec/io/label_set_io.h"
#include "semrec/io/mot_io.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/usd/usda_reader.h"

namespace fs = std::filesystem;

namespace semrec::eval {

void SceneResultOptions::Check() const {
  metrics.Check();
  CheckArgument(!result.empty(), "eval scene: no result given");
  CheckArgument(!gt.empty(), "eval scene: no ground truth given");
  CheckArgument(observed_stride >= 1,
                "eval scene: observed_stride must be >= 1");
}

std::map<std::string, int32_t> LoadClassMap(const fs::path& path,
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

namespace {

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

}  // namespace

// The transform that turned the result upright (T_upright_world), so that the
// ground truth can be brought into the result's frame. Every result with a
// scene (`semrec run`, `semrec mesh`) writes it into its layers'
// customLayerData. Identity only when no layer says the result was turned:
// guessing would score in the wrong frame without a word.
Transform ResultUprightTransform(const fs::path& scene) {
  std::string gravity;  // the layers' "gravity" method, if any
  for (const fs::path& layer : {scene, scene.parent_path() / "static.usda"}) {
    if (!fs::exists(layer)) continue;
    const auto data = usd::ReadCustomLayerData(layer);
    if (const auto it = data.find("gravity"); it != data.end()) {
      gravity = it->second;
    }
    if (const auto it = data.find("T_upright_world"); it != data.end()) {
      return ParseUpright(it->second, layer, "customLayerData T_upright_world");
    }
  }
  if (!gravity.empty() && gravity != "none") {
    throw FormatError(
        scene, fmt::format("the result was turned upright (gravity: {}) but "
                           "its layers' customLayerData have no "
                           "T_upright_world: cannot bring the ground truth "
                           "into its frame",
                           gravity));
  }
  return Transform();
}

std::string SceneResultEvaluation::ClassName(int32_t id) const {
  return id >= 0 && gt_classes.Contains(static_cast<uint16_t>(id))
             ? gt_classes.Get(static_cast<uint16_t>(id)).name
             : fmt::format("({})", id);
}

namespace {

// The result's world frame from the ground truth's: the identity for a
// result built from the recording's poses, the trajectory alignment's
// inverse for one built from estimated poses.
Transform ResultFromGroundTruth(const SceneResultOptions& options) {
  const fs::path poses = options.result / "poses.txt";
  if (!fs::is_directory(options.result) || !fs::exists(poses)) {
    return Transform();
  }
  if (options.gt_trajectory.empty()) {
    throw InvalidArgument(
        options.result.string() +
        " was built from estimated camera poses (poses.txt): give the "
        "recording's true trajectory (--gt-trajectory SEQUENCE|TUM file) to "
        "bring the ground truth into its frame");
  }
  const auto estimate = io::ReadTumTrajectory(poses);
  const auto truth =
      ReadTrajectory(options.gt_trajectory, options.gt_trajectory_options);
  spdlog::info("estimated poses aligned to {}: ATE RMSE {:.4f} m",
               options.gt_trajectory.string(),
               EvaluateTrajectory(estimate, truth).ate_rmse_m);
  return AlignPoses(estimate, truth).Inverse();
}

// `scene`'s frame (upright) from the ground truth's world frame.
Transform ResultFromGroundTruthWorld(const SceneResultOptions& options,
                                     const fs::path& scene) {
  return ResultUprightTransform(scene) * ResultFromGroundTruth(options);
}

}  // namespace

std::vector<Eigen::Vector3f> ResultSurfaceInWorld(
    const fs::path& result, const fs::path& gt_trajectory,
    const io::SequenceReaderOptions& gt_trajectory_options) {
  SceneResultOptions options;
  options.result = result;
  options.gt_trajectory = gt_trajectory;
  options.gt_trajectory_options = gt_trajectory_options;
  const fs::path scene =
      fs::is_directory(result) ? result / "scene.usda" : result;
  const Transform T_world_result =
      ResultFromGroundTruthWorld(options, scene).Inverse();
  std::vector<Eigen::Vector3f> points;
  for (const usd::MeshPrim& m : usd::ReadScene(scene)) {
    for (const Eigen::Vector3f& p : m.points) {
      points.push_back((T_world_result * p.cast<double>()).cast<float>());
    }
  }
  return points;
}

SceneResultEvaluation EvaluateSceneResult(const SceneResultOptions& options) {
  options.Check();
  SceneResultEvaluation out;
  const fs::path& result = options.result;
  out.scene = fs::is_directory(result) ? result / "scene.usda" : result;
  const fs::path& scene = out.scene;
  // The result is written upright (and, from estimated poses, in its own
  // world): the ground truth goes into its frame (found first: a result
  // without its transform fails before the slow work).
  const Transform T_result_gt = ResultFromGroundTruthWorld(options, scene);
  SceneGroundTruth gt = ReadSceneGroundTruth(options.gt);
  fs::path classes_file = options.gt_classes;
  if (classes_file.empty()) {
    classes_file = options.gt.parent_path() / "classes.json";
    if (!fs::exists(classes_file)) {
      throw IoError(classes_file,
                    "no classes.json beside the ground truth: give its "
                    "classes (--gt-classes FILE)");
    }
  }
  out.gt_classes = io::LoadLabelSet(classes_file.string());
  const LabelSet& gt_classes = out.gt_classes;
  const auto map = LoadClassMap(options.class_map, gt_classes);
  out.all_points = gt.points.size();
  if (!options.observed_in.empty()) {
    io::SequenceReaderOptions reader_options;
    reader_options.stride = options.observed_stride;
    const io::SequenceReader reader =
        io::SequenceReader::Open(options.observed_in, reader_options);
    gt.views = ObservedViews(gt.points, reader);
    std::vector<bool> seen(gt.views.size());
    for (size_t i = 0; i < seen.size(); ++i) seen[i] = gt.views[i] > 0;
    gt = Subset(gt, seen);
  }
  for (auto& p : gt.points) {
    p = (T_result_gt * p.cast<double>()).cast<float>();
  }

  std::vector<PredictedObject> predicted;
  for (const usd::MeshPrim& m : usd::ReadScene(scene)) {
    PredictedObject p;
    p.id = m.instance_id;
    p.score = static_cast<double>(m.point_count);
    p.surface = m.points;
    if (const auto it = map.find(m.label); it != map.end()) {
      p.class_id = it->second;
    } else if (const auto id = gt_classes.FindByName(m.label)) {
      p.class_id = *id;
    } else {
      ++out.unmapped[m.label];
    }
    predicted.push_back(std::move(p));
  }
  std::set<int32_t> things;
  for (const LabelClass& c : gt_classes.Classes()) {
    if (c.kind == ClassKind::kThing) things.insert(c.id);
  }
  out.metrics = EvaluateScene(gt, predicted, things, options.metrics);
  return out;
}

std::string SceneResultEvaluation::Text(const SceneResultOptions& options,
                                        bool per_object) const {
  const SceneMetrics& m = metrics;
  const auto name = [&](int32_t id) { return ClassName(id); };
  size_t split = 0;
  for (const auto& [object, pieces] : m.pieces_per_gt_object) {
    split += pieces > 1;
  }
  std::string text = fmt::format(
      "{} vs {}: {} ground-truth points{} ({:.1f}% within {} m of a "
      "predicted surface)\nmIoU {:.2f}  AP25 {:.2f}  AP50 {:.2f}  recall@0.5 "
      "{:.2f}  "
      "precision@0.5 {:.2f}  (percent)\n{} predicted objects for {} "
      "ground-truth objects ({:.2f} per object; {} objects in more than one "
      "piece)\n",
      scene.string(), options.gt.string(), m.gt_points,
      options.observed_in.empty()
          ? std::string()
          : fmt::format(" seen in {} (of {})", options.observed_in.string(),
                        all_points),
      m.gt_points ? 100.0 * static_cast<double>(m.covered_points) /
                        static_cast<double>(m.gt_points)
                  : 0.0,
      options.metrics.radius_m, 100 * m.mean_iou, 100 * m.ap25, 100 * m.ap50,
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
  if (per_object) {
    text += fmt::format(
        "\nwhere each ground-truth object's points went (predicted objects "
        "with >= 5%; views: the most frames that saw one of its points, with "
        "--observed-in):\n{:>5}  {:<16} {:>7} {:>5} {:>7} {:>9}  {}\n",
        "id", "class", "points", "views", "IoU", "uncovered",
        "predicted id:class share");
    for (const auto& o : m.objects) {
      std::string shares;
      for (const auto& s : o.shares) {
        shares += fmt::format(" {}:{} {:.0f}%", s.predicted_id,
                              name(s.class_id), 100 * s.share);
      }
      text += fmt::format("{:>5}  {:<16} {:>7} {:>5} {:>7.2f} {:>8.0f}% {}\n",
                          o.id, name(o.class_id), o.points,
                          o.views > 0 ? std::to_string(o.views) : "-",
                          100 * o.best_iou, 100 * o.uncovered, shares);
    }
  }
  return text;
}

nlohmann::json SceneResultEvaluation::ToJson() const {
  const SceneMetrics& m = metrics;
  const auto name = [&](int32_t id) { return ClassName(id); };
  const auto& unmapped = this->unmapped;
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
                       {"views", o.views},
                       {"shares", shares}});
  }
  nlohmann::json pieces = nlohmann::json::object();
  for (const auto& [object, n] : m.pieces_per_gt_object) {
    pieces[std::to_string(object)] = n;
  }
  return {{"gt_points", m.gt_points},
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
}

nlohmann::json MotMetricsJson(const MotMetrics& m) {
  return {{"frames", m.frames},
          {"gt_boxes", m.gt_boxes},
          {"gt_ids", m.gt_ids},
          {"predicted_boxes", m.predicted_boxes},
          {"predicted_ids", m.predicted_ids},
          {"mota", m.mota},
          {"motp", m.motp},
          {"idf1", m.idf1},
          {"idp", m.idp},
          {"idr", m.idr},
          {"precision", m.precision},
          {"recall", m.recall},
          {"fp", m.false_positives},
          {"fn", m.false_negatives},
          {"id_switches", m.id_switches},
          {"fragmentations", m.fragmentations},
          {"mostly_tracked", m.mostly_tracked},
          {"partially_tracked", m.partially_tracked},
          {"mostly_lost", m.mostly_lost},
          {"hota", m.hota},
          {"deta", m.deta},
          {"assa", m.assa}};
}

MotMetrics EvaluateMotFiles(const fs::path& gt, const fs::path& result) {
  return EvaluateMot(io::ReadMotFile(gt), io::ReadMotFile(result));
}

SegMetrics EvaluateSegFolders(const fs::path& pred, const fs::path& gt,
                              const LabelSet& labels,
                              const SegEvalOptions& options) {
  options.Check();
  SegEvaluator evaluator(options);
  for (const auto& [pred_file, gt_file] : MatchSegFiles(pred, gt)) {
    const LabelMap p = io::ReadLabelImage(pred_file);
    LabelMap g = io::ReadLabelImage(gt_file);
    FoldUnnamedIntoCatchAll(labels, &g);
    if (!p.SameSize(g)) {
      throw FormatError(
          pred_file,
          fmt::format("is {}x{} but the ground truth {} is {}x{}", p.width(),
                      p.height(), gt_file.string(), g.width(), g.height()));
    }
    evaluator.Add(p, g);
  }
  return evaluator.Result();
}

nlohmann::json SegMetricsJson(const SegMetrics& m, const LabelSet& labels) {
  nlohmann::json classes = nlohmann::json::array();
  for (const auto& c : m.classes) {
    classes.push_back(
        {{"id", c.id},
         {"name", labels.Contains(c.id) ? labels.Get(c.id).name
                                        : "(not in " + labels.name() + ")"},
         {"iou", c.iou},
         {"accuracy", c.accuracy},
         {"gt_pixels", c.gt_pixels},
         {"pred_pixels", c.pred_pixels},
         {"boundary_iou", c.boundary_iou},
         {"boundary_f", c.boundary_f}});
  }
  return {{"images", m.images},
          {"pixel_accuracy", m.pixel_accuracy},
          {"mean_iou", m.mean_iou},
          {"mean_accuracy", m.mean_accuracy},
          {"mean_boundary_iou", m.mean_boundary_iou},
          {"mean_boundary_f", m.mean_boundary_f},
          {"classes", classes}};
}

std::string MotMetricsText(const MotMetrics& m, const std::string& result,
                           const std::string& gt) {
  return fmt::format(
      "{} vs {}: {} frames, {} gt boxes ({} ids), {} predicted ({} ids)\n"
      "  MOTA {:.4f}  MOTP {:.4f}  IDF1 {:.4f}  IDP {:.4f}  IDR {:.4f}\n"
      "  precision {:.4f}  recall {:.4f}  FP {}  FN {}  IDsw {}  Frag {}"
      "  MT/PT/ML {}/{}/{}\n"
      "  HOTA {:.4f}  DetA {:.4f}  AssA {:.4f}\n",
      result, gt, m.frames, m.gt_boxes, m.gt_ids, m.predicted_boxes,
      m.predicted_ids, m.mota, m.motp, m.idf1, m.idp, m.idr, m.precision,
      m.recall, m.false_positives, m.false_negatives, m.id_switches,
      m.fragmentations, m.mostly_tracked, m.partially_tracked, m.mostly_lost,
      m.hota, m.deta, m.assa);
}

nlohmann::json DistanceStatsJson(const DistanceStats& s) {
  return {{"points", s.count},       {"mean_mm", s.mean_m * 1e3},
          {"std_mm", s.std_m * 1e3}, {"median_mm", s.median_m * 1e3},
          {"rms_mm", s.rms_m * 1e3}, {"max_mm", s.max_m * 1e3}};
}

std::string DistanceStatsText(const DistanceStats& s,
                              const std::string& estimate,
                              const std::string& reference,
                              size_t reference_points) {
  return fmt::format(
      "C2C {} -> {} ({} points, reference {}):\n"
      "  mean {:.3f} mm  std {:.3f} mm  median {:.3f} mm  rms {:.3f} mm  "
      "max {:.3f} mm\n",
      estimate, reference, s.count, reference_points, s.mean_m * 1e3,
      s.std_m * 1e3, s.median_m * 1e3, s.rms_m * 1e3, s.max_m * 1e3);
}

std::string SegMetricsText(const SegMetrics& m, const LabelSet& labels,
                           int boundary_tolerance_px) {
  std::string text = fmt::format(
      "{} images, {} labelled pixels\npAcc {:.2f}  mIoU {:.2f}  mAcc {:.2f}  "
      "boundary IoU {:.2f}  boundary F@{}px {:.2f}  (percent)\n\n"
      "{:>5}  {:<24} {:>7} {:>7} {:>8} {:>7}\n",
      m.images, m.valid_pixels, 100 * m.pixel_accuracy, 100 * m.mean_iou,
      100 * m.mean_accuracy, 100 * m.mean_boundary_iou, boundary_tolerance_px,
      100 * m.mean_boundary_f, "id", "class", "IoU", "Acc", "bIoU", "bF");
  for (const auto& c : m.classes) {
    const std::string name = labels.Contains(c.id)
                                 ? labels.Get(c.id).name
                                 : "(not in " + labels.name() + ")";
    text += fmt::format("{:>5}  {:<24} {:>7.2f} {:>7.2f} {:>8.2f} {:>7.2f}\n",
                        c.id, name, 100 * c.iou, 100 * c.accuracy,
                        100 * c.boundary_iou, 100 * c.boundary_f);
  }
  return text;
}

}  // namespace semrec::eval
