// `semrec eval c2c <estimate.ply> <reference.ply>`: cloud-to-cloud distance.
#include <cstdio>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "semrec/core/file_util.h"
#include "semrec/eval/c2c.h"
#include "semrec/eval/mot.h"
#include "semrec/io/mot_io.h"
#include "semrec/io/ply_io.h"

namespace semrec::cli {
namespace {

struct C2cArgs {
  std::string estimate;
  std::string reference;
  bool json = false;
  std::string per_point;
};

void RunC2c(const C2cArgs& args) {
  const io::PlyData estimate = io::ReadPly(args.estimate);
  const io::PlyData reference = io::ReadPly(args.reference);
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
    std::printf("%s\n", nlohmann::json({{"points", s.count},
                                        {"mean_mm", s.mean_m * 1e3},
                                        {"std_mm", s.std_m * 1e3},
                                        {"median_mm", s.median_m * 1e3},
                                        {"rms_mm", s.rms_m * 1e3},
                                        {"max_mm", s.max_m * 1e3}})
                            .dump(2)
                            .c_str());
    return;
  }
  std::printf(
      "%s",
      fmt::format(
          "C2C {} -> {} ({} points, reference {}):\n"
          "  mean {:.3f} mm  std {:.3f} mm  median {:.3f} mm  rms {:.3f} mm  "
          "max {:.3f} mm\n",
          args.estimate, args.reference, s.count, reference.points.size(),
          s.mean_m * 1e3, s.std_m * 1e3, s.median_m * 1e3, s.rms_m * 1e3,
          s.max_m * 1e3)
          .c_str());
}

struct MotArgs {
  std::string gt;
  std::string result;
  bool json = false;
};

void RunMot(const MotArgs& args) {
  const eval::MotMetrics m =
      eval::EvaluateMot(io::ReadMotFile(args.gt), io::ReadMotFile(args.result));
  const nlohmann::json j = {{"frames", m.frames},
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
  if (args.json) {
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  std::printf(
      "%s",
      fmt::format(
          "{} vs {}: {} frames, {} gt boxes ({} ids), {} predicted ({} ids)\n"
          "  MOTA {:.4f}  MOTP {:.4f}  IDF1 {:.4f}  IDP {:.4f}  IDR {:.4f}\n"
          "  precision {:.4f}  recall {:.4f}  FP {}  FN {}  IDsw {}  Frag {}"
          "  MT/PT/ML {}/{}/{}\n"
          "  HOTA {:.4f}  DetA {:.4f}  AssA {:.4f}\n",
          args.result, args.gt, m.frames, m.gt_boxes, m.gt_ids,
          m.predicted_boxes, m.predicted_ids, m.mota, m.motp, m.idf1, m.idp,
          m.idr, m.precision, m.recall, m.false_positives, m.false_negatives,
          m.id_switches, m.fragmentations, m.mostly_tracked,
          m.partially_tracked, m.mostly_lost, m.hota, m.deta, m.assa)
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
  c2c->add_option("estimate", args->estimate, "Estimated cloud (PLY)")
      ->required();
  c2c->add_option("reference", args->reference, "Reference cloud (PLY)")
      ->required();
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
}

}  // namespace semrec::cli
