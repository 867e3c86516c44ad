// Full-frame segmentation cost, step by step: the hybrid segmenter as
// `semrec segment` ran it formerly (dense stride 2, the reference)
// against the default and variants that decode fewer mask prompts, on the same
// frames in one process. Per step: time per frame, prompts decoded, and whether
// the masks hold: the share of the reference's instances (>= 1000 px)
// recovered at IoU >= 0.8 and the per-pixel agreement of the voted classes
// with the reference's output.
//   bench_prompts [image ...]   (default: 7-Scenes chess, Redwood, 3DMatch)
// Needs the real models (scripts/setup).
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "bench_util.h"
#include "semrec/core/stopwatch.h"
#include "semrec/io/image_io.h"
#include "semrec/sam/kernel_ops.h"
#include "semrec/segment/hybrid_segmenter.h"

namespace fs = std::filesystem;
using namespace semrec;

namespace {

struct Step {
  std::string name;
  std::function<void(segment::HybridSegmenterOptions*)> apply;
};

struct Outcome {
  double seconds = 0;
  double encode_seconds = 0;  // the image encoder
  double decode_seconds = 0;  // the mask prompts
  int prompts = 0;
  size_t masks = 0;
};

// The reference's instances of >= min_px pixels and how many a result
// recovers at IoU >= 0.8 (best-matching instance).
std::pair<size_t, size_t> Recovered(const LabelMap& reference,
                                    const LabelMap& now, size_t min_px) {
  size_t large = 0, found = 0;
  for (const auto& [id, m] :
       bench::MatchInstances(reference, now, [](size_t) { return true; })) {
    if (m.area < min_px) continue;
    ++large;
    found += m.best_iou >= 0.8;
  }
  return {large, found};
}

int Run(int argc, char** argv) {
  std::vector<fs::path> images;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--help") {
      std::printf(
          "bench_prompts [image ...]\n  Full-frame hybrid segmentation: "
          "the former defaults vs fewer mask prompts, per step time, prompts, "
          "masks recovered and class agreement (default images: 7-Scenes "
          "chess, Redwood, 3DMatch from ../shared/data).\n");
      return 0;
    }
    images.emplace_back(argv[i]);
  }
  if (images.empty()) {
    const fs::path data = bench::SampleDataDir();
    const fs::path chess = data / "7scenes_chess_0_99";
    images = {chess / "frame-000000.color.jpg",
              chess / "frame-000050.color.jpg",
              chess / "frame-000099.color.jpg",
              data / "redwood_livingroom1_5" / "color" / "00000.jpg",
              data / "3dmatch_5" / "seq-01" / "frame-000000.color.png"};
  }
  const auto registry = infer::ModelRegistry::LoadDefault();
  segment::HybridSegmenterOptions defaults;
  defaults.objects.model = "yolox_nano";  // as `semrec segment` runs
  // The first step is the reference (the former default); the others are
  // the default and variants of it, each compared with the reference.
  using Kernel = segment::PromptableOptions::Kernel;
  // The former default: ONNX Runtime's workers spinning between operators.
  const auto before = [](segment::HybridSegmenterOptions* o) {
    o->masks.rejected_inside_similarity = 1.0f;
    o->masks.dense_stride = 2;
    o->masks.covered_similarity = 0.8f;
    o->masks.model.mask_margin_logits = 0.0f;
    o->masks.model.decoder_kernel = Kernel::kOff;
  };
  const auto spin = [](segment::HybridSegmenterOptions* o) {
    o->semantic.runtime.spin_between_ops = true;
    o->masks.model.runtime.spin_between_ops = true;
    o->objects.runtime.spin_between_ops = true;
  };
  const std::vector<Step> steps = {
      {"stride 2, covered 0.8 (before)",
       [&](auto* o) {
         before(o);
         spin(o);
       }},
      {"+ ONNX Runtime workers sleep", [&](auto* o) { before(o); }},
      {"+ stride 4, covered 0.6",
       [](auto* o) {
         o->masks.rejected_inside_similarity = 1.0f;
         o->masks.model.mask_margin_logits = 0.0f;
         o->masks.model.decoder_kernel = Kernel::kOff;
       }},
      {"+ mask margin 8",
       [](auto* o) {
         o->masks.rejected_inside_similarity = 1.0f;
         o->masks.model.decoder_kernel = Kernel::kOff;
       }},
      {"+ decoder kernel (fp32)",
       [](auto* o) {
         o->masks.rejected_inside_similarity = 1.0f;
         o->masks.model.decoder_kernel = Kernel::kOn;
         o->masks.model.kernel_upscales = false;
       }},
      {sam::kernel_ops::HasBf16() ? "+ bf16 products" : "ONNX Runtime upscales",
       [](auto* o) {
         o->masks.rejected_inside_similarity = 1.0f;
         o->masks.model.kernel_upscales = false;
       }},
      {sam::kernel_ops::HasBf16() ? "+ upscaling in kernel"
                                  : "kernel upscales (no bf16 here)",
       [](auto* o) { o->masks.rejected_inside_similarity = 1.0f; }},
      {"+ skip inside rejected (default)", [](auto*) {}},
      {"default, inside sim. 0.6 logit 0",
       [](auto* o) {
         o->masks.rejected_inside_similarity = 0.6f;
         o->masks.rejected_inside_logit = 0.0f;
       }},
      {"default + rejected sim. 0.6",
       [](auto* o) { o->masks.rejected_similarity = 0.6f; }},
      {"default + rejected sim. 0",
       [](auto* o) { o->masks.rejected_similarity = 0.0f; }},
  };

  // Each step's segmenter is made just before its run and dropped after it:
  // with all of them alive at once the later steps ran slower (the same
  // encoder 0.44 s per frame in the first steps, 0.50 s in the last), an
  // effect of the bench, not of the steps.
  std::vector<segment::HybridSegmenterOptions> options;
  for (const Step& s : steps) {
    segment::HybridSegmenterOptions o = defaults;
    s.apply(&o);
    o.Check();
    options.push_back(o);
  }
  std::vector<Outcome> total(steps.size());
  std::vector<size_t> large(steps.size()), found(steps.size());
  std::vector<double> agree(steps.size());
  size_t pixels = 0;
  for (const fs::path& path : images) {
    const ColorImage rgb = io::ReadColorImage(path);
    std::printf("%s %dx%d\n", path.filename().string().c_str(), rgb.width(),
                rgb.height());
    segment::HybridResult first;
    for (size_t s = 0; s < steps.size(); ++s) {
      segment::HybridSegmenter segmenter(registry, options[s]);
      const Stopwatch t;
      segment::HybridResult r = segmenter.Segment(rgb);
      const double seconds = t.Elapsed();
      total[s].seconds += seconds;
      total[s].prompts += r.mask_stats.prompts_decoded;
      total[s].encode_seconds += r.mask_stats.encode_seconds;
      total[s].decode_seconds += r.mask_stats.decode_seconds;
      total[s].masks += r.masks.size();
      if (s == 0) first = r;
      const auto [l, f] = Recovered(first.vote.instance, r.vote.instance, 1000);
      size_t same = 0;
      for (size_t i = 0; i < rgb.NumPixels(); ++i) {
        same += first.vote.semantic.values()[i] == r.vote.semantic.values()[i];
      }
      large[s] += l;
      found[s] += f;
      agree[s] += static_cast<double>(same);
      std::printf(
          "  %-32s %6.2f s %5d prompts %4zu masks  %zu/%zu recovered "
          "%.1f%% agree\n",
          steps[s].name.c_str(), seconds, r.mask_stats.prompts_decoded,
          r.masks.size(), f, l,
          100.0 * static_cast<double>(same) / rgb.NumPixels());
    }
    pixels += rgb.NumPixels();
  }
  std::printf("\n%-32s %10s %8s %8s %8s %8s %10s %9s\n", "step (all images)",
              "s/frame", "encode", "decode", "prompts", "speed-up", "recovered",
              "agree");
  const double n = static_cast<double>(images.size());
  for (size_t s = 0; s < steps.size(); ++s) {
    std::printf("%-32s %10.2f %8.2f %8.2f %8.0f %7.2fx %9.1f%% %8.1f%%\n",
                steps[s].name.c_str(), total[s].seconds / n,
                total[s].encode_seconds / n, total[s].decode_seconds / n,
                total[s].prompts / n, total[0].seconds / total[s].seconds,
                100.0 * static_cast<double>(found[s]) /
                    static_cast<double>(std::max<size_t>(1, large[s])),
                100.0 * agree[s] / static_cast<double>(pixels));
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_prompts: %s\n", e.what());
    return 1;
  }
}
