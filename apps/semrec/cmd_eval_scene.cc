// `semrec eval scene <result-dir> <gt.ply>`: 3D semantic and instance quality
// of a reconstructed scene against a labelled ground-truth cloud.
#include <cstdio>

#include <fmt/format.h>

#include "commands.h"
#include "semrec/eval/scene_result.h"

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

void RunScene(const SceneArgs& args) {
  CheckUsage(args.options);
  eval::SceneResultOptions options;
  options.result = args.result;
  options.gt = args.gt;
  options.gt_classes = args.gt_classes;
  options.class_map = args.class_map;
  options.observed_in = args.observed_in;
  options.observed_stride = args.observed_stride;
  options.metrics = args.options;
  CheckUsage(options);
  const eval::SceneResultEvaluation e = eval::EvaluateSceneResult(options);
  if (args.json) {
    std::printf("%s\n", e.ToJson().dump(2).c_str());
    return;
  }
  const eval::SceneMetrics& m = e.metrics;
  const auto name = [&](int32_t id) { return e.ClassName(id); };
  const fs::path& scene = e.scene;
  const size_t all_points = e.all_points;
  const auto& unmapped = e.unmapped;
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
