// `semrec eval scene <result-dir> <gt.ply>`: 3D semantic and instance quality
// of a reconstructed scene against a labelled ground-truth cloud.
#include <cstdio>

#include "commands.h"
#include "semrec/eval/scene_result.h"

namespace semrec::cli {
namespace {

struct SceneArgs {
  std::string result;
  std::string gt;
  std::string gt_classes;
  std::string class_map;
  std::string observed_in;
  int observed_stride = 1;
  std::string gt_trajectory;
  std::string pose_correction;
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
  options.gt_trajectory = args.gt_trajectory;
  options.gt_trajectory_options.pose_correction_path = args.pose_correction;
  options.metrics = args.options;
  CheckUsage(options);
  const eval::SceneResultEvaluation e = eval::EvaluateSceneResult(options);
  if (args.json) {
    std::printf("%s\n", e.ToJson().dump(2).c_str());
    return;
  }
  std::printf("%s", e.Text(options, args.objects).c_str());
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
  cmd->add_option("--gt-trajectory", args->gt_trajectory,
                  "For a result built from estimated poses (poses.txt in its "
                  "folder): the recording's true trajectory (the sequence or "
                  "a TUM file), to which they are aligned");
  cmd->add_option("--pose-correction", args->pose_correction,
                  "The --gt-trajectory sequence's pose correction (YAML)");
  cmd->add_option("--radius-m", args->options.radius_m,
                  "Label transfer radius (m)")
      ->capture_default_str();
  cmd->add_flag("--json", args->json, "Print JSON");
  cmd->callback([args] { RunScene(*args); });
}

}  // namespace semrec::cli
