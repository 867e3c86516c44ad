// `semrec eval c2c|mot|seg` (`scene`: cmd_eval_scene.cc, `traj`:
// cmd_eval_traj.cc): cloud-to-cloud distance, tracking and segmentation
// metrics.
#include <cstdio>
#include <filesystem>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "semrec/core/file_util.h"
#include "semrec/eval/c2c.h"
#include "semrec/eval/mot.h"
#include "semrec/eval/scene_result.h"
#include "semrec/eval/seg_metrics.h"
#include "semrec/io/image_io.h"
#include "semrec/io/label_set_io.h"
#include "semrec/io/mot_io.h"
#include "semrec/io/ply_io.h"

namespace semrec::cli {
namespace {

struct C2cArgs {
  std::string estimate;
  std::string reference;
  bool json = false;
  std::string per_point;
  std::string gt_trajectory;
};

// A PLY's points, or a result folder's surface in the recording's world.
io::PlyData Cloud(const std::string& path, const C2cArgs& args) {
  if (!std::filesystem::is_directory(path)) return io::ReadPly(path);
  io::PlyData out;
  out.points = eval::ResultSurfaceInWorld(path, args.gt_trajectory);
  return out;
}

void RunC2c(const C2cArgs& args) {
  const io::PlyData estimate = Cloud(args.estimate, args);
  const io::PlyData reference = Cloud(args.reference, args);
  const std::vector<double> distances =
      eval::CloudToCloudDistances(estimate.points, reference.points);
  if (!args.per_point.empty()) {
    std::string text;
    text.reserve(distances.size() * 48);
    for (size_t i = 0; i < distances.size(); ++i) {
      const auto& p = estimate.points[i];
      text += fmt::format("{:.6f} {:.6f} {:.6f} {:.8f}\n", p.x(), p.y(), p.z(),
                          distances[i]);
    }
    WriteTextFileAtomic(args.per_point, text);
  }
  const eval::DistanceStats s = eval::Summarize(distances);
  if (args.json) {
    std::printf("%s\n", eval::DistanceStatsJson(s).dump(2).c_str());
    return;
  }
  std::printf("%s", eval::DistanceStatsText(s, args.estimate, args.reference,
                                            reference.points.size())
                        .c_str());
}

struct MotArgs {
  std::string gt;
  std::string result;
  bool json = false;
};

void RunMot(const MotArgs& args) {
  const eval::MotMetrics m = eval::EvaluateMotFiles(args.gt, args.result);
  if (args.json) {
    std::printf("%s\n", eval::MotMetricsJson(m).dump(2).c_str());
    return;
  }
  std::printf("%s", eval::MotMetricsText(m, args.result, args.gt).c_str());
}

struct SegArgs {
  std::string pred;
  std::string gt;
  std::string labels = "ade20k";
  bool json = false;
  eval::SegEvalOptions options;
};

void RunSeg(const SegArgs& args) {
  CheckUsage(args.options);
  const LabelSet labels = io::LoadLabelSet(args.labels);
  const eval::SegMetrics m =
      eval::EvaluateSegFolders(args.pred, args.gt, labels, args.options);
  if (args.json) {
    std::printf("%s\n", eval::SegMetricsJson(m, labels).dump(2).c_str());
    return;
  }
  std::printf(
      "%s", eval::SegMetricsText(m, labels, args.options.boundary_tolerance_px)
                .c_str());
}

}  // namespace

void RegisterEval(CLI::App& app) {
  CLI::App* eval =
      app.add_subcommand("eval", "Evaluate results against ground truth.");
  eval->require_subcommand(1);
  auto args = std::make_shared<C2cArgs>();
  CLI::App* c2c =
      eval->add_subcommand("c2c",
                           "Cloud-to-cloud distance (as CloudCompare's C2C): "
                           "for each estimate point, the distance "
                           "to the nearest reference point; prints mean, std, "
                           "median, rms and max in mm.");
  c2c->add_option("estimate", args->estimate,
                  "Estimated cloud (PLY), or a run's output folder (its "
                  "scene's mesh vertices, in the recording's world frame)")
      ->required();
  c2c->add_option("reference", args->reference,
                  "Reference cloud (PLY) or output folder")
      ->required();
  c2c->add_option("--gt-trajectory", args->gt_trajectory,
                  "For an output folder built from estimated poses: the "
                  "recording (or a TUM file) whose poses they are aligned to");
  c2c->add_flag("--json", args->json, "Print JSON");
  c2c->add_option(
      "--per-point", args->per_point,
      "Also write 'x y z distance_m' per estimate point to this text file");
  c2c->callback([args] { RunC2c(*args); });

  auto mot_args = std::make_shared<MotArgs>();
  CLI::App* mot =
      eval->add_subcommand("mot",
                           "Tracking metrics with MOTChallenge conventions "
                           "(IoU >= 0.5): CLEAR MOT (MOTA, MOTP, FP, "
                           "FN, ID switches, fragmentations, MT/PT/ML), "
                           "IDF1/IDP/IDR and HOTA/DetA/AssA.");
  mot->add_option("gt", mot_args->gt, "Ground truth (MOTChallenge gt.txt)")
      ->required();
  mot->add_option("result", mot_args->result,
                  "Tracker output (MOTChallenge format)")
      ->required();
  mot->add_flag("--json", mot_args->json, "Print JSON");
  mot->callback([mot_args] { RunMot(*mot_args); });

  auto seg_args = std::make_shared<SegArgs>();
  CLI::App* seg = eval->add_subcommand(
      "seg",
      "Semantic segmentation metrics over label PNGs matched by file name "
      "(ADE20K conventions: ground-truth 0 and 255 are ignored): pAcc, mIoU, "
      "mAcc, Boundary IoU (Cheng et al. 2021) and boundary F-score, plus a "
      "per-class table.");
  seg->add_option("pred", seg_args->pred,
                  "Predicted label PNGs (or a `semrec segment` output folder)")
      ->required();
  seg->add_option("gt", seg_args->gt, "Ground-truth label PNGs")->required();
  seg->add_option(
         "--labels", seg_args->labels,
         "Label set: voc, ade20k, ade20k-top31, coco, cityscapes or a JSON "
         "file. With a catch-all class 0 (ade20k-top31's 'other'), "
         "ground-truth classes the set does not name count as it")
      ->capture_default_str();
  seg->add_option("--boundary-tolerance-px",
                  seg_args->options.boundary_tolerance_px,
                  "Boundary F-score tolerance (pixels)")
      ->capture_default_str();
  seg->add_option("--boundary-dilation-ratio",
                  seg_args->options.boundary_dilation_ratio,
                  "Boundary IoU band width as a fraction of the diagonal")
      ->capture_default_str();
  seg->add_flag(
      "--no-ignore-zero",
      [seg_args](int64_t) { seg_args->options.ignore_zero = false; },
      "Count label 0 as a class (VOC background)");
  seg->add_flag("--json", seg_args->json, "Print JSON");
  seg->callback([seg_args] { RunSeg(*seg_args); });

  AddEvalScene(eval);
  AddEvalTraj(eval);
}

}  // namespace semrec::cli
