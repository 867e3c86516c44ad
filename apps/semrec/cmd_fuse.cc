// `semrec fuse <sequence> --labels gt|DIR|single:CLASS --out DIR`:
// semantics-guided fusion.
#include <cstdio>
#include <map>

#include <fmt/format.h>

#include "commands.h"
#include "semrec/core/error.h"
#include "semrec/fuse/fuse_sequence.h"

namespace semrec::cli {
namespace {

struct FuseArgs {
  SequenceArgs sequence;
  std::string labels = "gt";
  std::string out;
  fuse::FusionOptions fusion;
  fuse::SegmentExtractionOptions extraction;
  bool no_gating = false;
  std::string method = "fast";
  double max_depth_m = 4.0;
  bool overwrite = false;
  std::string merge = "voxel";
};

void RunFuse(FuseArgs args) {
  if (args.method != "fast" && args.method != "brute_force") {
    throw UsageError("--method must be 'fast' or 'brute_force', got '" +
                     args.method + "'");
  }
  args.fusion.method = args.method == "fast"
                           ? fuse::FusionOptions::Method::kFast
                           : fuse::FusionOptions::Method::kBruteForce;
  args.fusion.label_gating = !args.no_gating;
  args.fusion.merge = fuse::ParseMerge(args.merge);
  CheckUsage(args.fusion);
  CheckUsage(args.extraction);
  io::SequenceReaderOptions reader_options = args.sequence.ReaderOptions();
  reader_options.max_depth_m = args.max_depth_m;
  const io::SequenceReader reader =
      io::SequenceReader::Open(args.sequence.path, reader_options);
  const auto source = fuse::SegmentationSource::Create(args.labels, reader);
  fuse::SceneFusion fusion(args.fusion);
  const fuse::FuseSequenceResult result =
      fuse::FuseSequence(reader, *source, args.extraction, &fusion);
  fuse::WriteFusionResult(args.out, fusion, source->classes(), result,
                          fmt::format("{} ({} layout, {} frames), labels {}",
                                      reader.root().string(), reader.layout(),
                                      reader.size(), args.labels),
                          args.overwrite);
  std::map<std::string, int> per_class;
  size_t points = 0;
  for (const auto& s : fusion.segments()) {
    ++per_class[source->classes().Get(s.class_id).name];
    points += s.points.size();
  }
  std::string classes;
  for (const auto& [name, n] : per_class) {
    classes += fmt::format("{}{} {}", classes.empty() ? "" : ", ", n, name);
  }
  std::printf(
      "%s",
      fmt::format(
          "{} frames -> {} segments ({} points): {}\nwrote {} in {:.2f} s\n",
          reader.size(), fusion.segments().size(), points, classes, args.out,
          result.seconds)
          .c_str());
}

}  // namespace

void RegisterFuse(CLI::App& app) {
  auto args = std::make_shared<FuseArgs>();
  CLI::App* cmd =
      app.add_subcommand("fuse",
                         "Semantics-guided point-cloud fusion: back-project "
                         "each frame's segments, merge them with "
                         "scene segments of the same class whose overlap sigma "
                         "= |mutual closest pairs| / "
                         "min(|a|, |b|) exceeds alpha. Writes one PLY per "
                         "fused segment, fused.ply and "
                         "summary.json.");
  AddSequenceArgs(cmd, &args->sequence);
  cmd->add_option("--labels", args->labels,
                  "Segmentation: 'gt' (the sequence's instance/semantic "
                  "layers), a folder with "
                  "instance/, semantic/ and classes.json, or 'single:<class>'")
      ->capture_default_str();
  cmd->add_option("--out,-o", args->out, "Output folder")->required();
  cmd->add_option("--alpha", args->fusion.alpha, "Merge when sigma > alpha")
      ->capture_default_str();
  cmd->add_option("--corr-voxel-m", args->fusion.corr_voxel_size_m,
                  "Voxel size of the overlap test (m)")
      ->capture_default_str();
  cmd->add_option("--store-voxel-m", args->fusion.store_voxel_size_m,
                  "Voxel size of the stored clouds (m)")
      ->capture_default_str();
  cmd->add_option("--max-corr-dist-m", args->fusion.max_corr_dist_m,
                  "Farthest mutually closest pair that counts (m)")
      ->capture_default_str();
  cmd->add_option("--merge", args->merge,
                  "paper: the paper's rule alone; evidence: also merge what "
                  "views show inside one mask, vote classes, fold fragments; "
                  "voxel: evidence, then objects decided per map voxel by "
                  "every view (structure only on its planes, fragments by "
                  "visibility)")
      ->check(CLI::IsMember({"paper", "evidence", "voxel"}))
      ->capture_default_str();
  cmd->add_flag("--no-gating", args->no_gating,
                "Compare segments of all classes (for comparison)");
  cmd->add_option("--method", args->method,
                  "fast or brute_force (identical results)")
      ->capture_default_str();
  cmd->add_option("--pixel-stride", args->extraction.pixel_stride,
                  "Back-project every n-th pixel")
      ->capture_default_str();
  cmd->add_option("--min-segment-points", args->extraction.min_points,
                  "Skip frame segments with fewer points")
      ->capture_default_str();
  cmd->add_option("--max-depth-m", args->max_depth_m,
                  "Ignore depth beyond this (m)")
      ->capture_default_str();
  cmd->add_flag("--overwrite", args->overwrite,
                "Write into a non-empty output folder");
  cmd->callback([args] { RunFuse(*args); });
}

}  // namespace semrec::cli
