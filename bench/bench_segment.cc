// Segmentation benchmark: automatic mask generation (fast vs the
// straightforward reference, with the masks' agreement), the vote, and the
// semantic branch, on real images.
//   bench_segment [--decoder-only] [image ...]
// (default: Redwood + ADE20K samples; --decoder-only: the per-prompt decoder
// timings on the first image only).
// Needs the real models (scripts/setup).
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "semrec/core/random.h"
#include "semrec/core/stopwatch.h"
#include "semrec/io/image_io.h"
#include "semrec/segment/mask_generator.h"
#include "semrec/segment/promptable.h"
#include "semrec/segment/semantic_segmenter.h"
#include "semrec/segment/vote.h"

namespace fs = std::filesystem;
using namespace semrec;

namespace {

struct Agreement {
  double mean_best_iou = 0;  // reference masks' best IoU with a fast mask
  double recall_50 = 0, recall_75 = 0;
  double precision_50 = 0;  // fast masks with IoU >= 0.5 to a reference one
};

double BestIou(const segment::Mask& m, const std::vector<segment::Mask>& set) {
  double best = 0;
  for (const auto& o : set) {
    if (segment::BoxIoU(m.box, o.box) > 0) {
      best = std::max(best, segment::MaskIoU(m, o));
    }
  }
  return best;
}

Agreement Compare(const std::vector<segment::Mask>& reference,
                  const std::vector<segment::Mask>& fast) {
  Agreement a;
  for (const auto& r : reference) {
    const double iou = BestIou(r, fast);
    a.mean_best_iou += iou;
    a.recall_50 += iou >= 0.5;
    a.recall_75 += iou >= 0.75;
  }
  for (const auto& f : fast) a.precision_50 += BestIou(f, reference) >= 0.5;
  if (!reference.empty()) {
    a.mean_best_iou /= reference.size();
    a.recall_50 /= reference.size();
    a.recall_75 /= reference.size();
  }
  if (!fast.empty()) a.precision_50 /= fast.size();
  return a;
}

void BenchVote() {
  // 640 x 480, 200 random disc masks, 21 classes.
  Rng rng(1);
  LabelMap semantic(640, 480);
  for (auto& v : semantic.values()) {
    v = static_cast<uint16_t>(rng.UniformInt(0, 20));
  }
  std::vector<segment::Mask> masks;
  for (int m = 0; m < 200; ++m) {
    Image<uint8_t> img(640, 480);
    const int cx = static_cast<int>(rng.UniformInt(0, 639)),
              cy = static_cast<int>(rng.UniformInt(0, 479));
    const int r = static_cast<int>(rng.UniformInt(5, 80));
    for (int y = std::max(0, cy - r); y < std::min(480, cy + r); ++y) {
      for (int x = std::max(0, cx - r); x < std::min(640, cx + r); ++x) {
        img(x, y) = (x - cx) * (x - cx) + (y - cy) * (y - cy) <= r * r;
      }
    }
    masks.push_back(segment::MaskFromImage(img));
  }
  segment::Vote(semantic, masks);  // warm-up
  const int runs = 20;
  const Stopwatch t;
  for (int i = 0; i < runs; ++i) segment::Vote(semantic, masks);
  std::printf("vote: 640x480, 200 masks: %.2f ms per image (target < 20 ms)\n",
              1000 * t.Elapsed() / runs);
}

// One decoder call per prompt on one thread: the SAM export as is vs the
// image/prompt split made at setup (scripts/split_sam_decoder.py), on the
// same prompts, alternating so that both see the same machine state.
void BenchDecoder(const infer::ModelRegistry& registry, const ColorImage& rgb) {
  segment::PromptableOptions options;
  auto split = segment::PromptableSegmenter::Create(registry, options);
  options.split_decoder = false;
  auto whole = segment::PromptableSegmenter::Create(registry, options);
  whole->SetImage(rgb);  // warm-up: first runs allocate
  split->SetImage(rgb);
  Stopwatch t;
  whole->SetImage(rgb);
  const double whole_image_s = t.Elapsed();
  t.Lap();
  split->SetImage(rgb);
  const double split_image_s = t.Elapsed();
  double whole_s = 0, split_s = 0, stopped_s = 0;
  segment::MaskFilter reject_all;  // every prompt stops on its preview
  reject_all.min_predicted_iou = 2.0f;
  const int n = 48;
  for (int i = 0; i < n; ++i) {
    const int column = i % 8, row = i / 8;  // an 8 x 6 grid
    segment::Prompt prompt;
    prompt.points = {{(static_cast<float>(column) + 0.5f) * rgb.width() / 8,
                      (static_cast<float>(row) + 0.5f) * rgb.height() / 6}};
    prompt.labels = {1};
    t.Lap();
    whole->Decode(prompt);
    whole_s += t.Elapsed();
    t.Lap();
    split->Decode(prompt);
    split_s += t.Elapsed();
    t.Lap();
    split->DecodeUnlessRejected(prompt, reject_all);
    stopped_s += t.Elapsed();
  }
  std::printf(
      "decoder, 1 thread, %d prompts: export %.1f ms/prompt, split %.1f "
      "ms/prompt (%.2fx), stopped on the preview %.1f ms/prompt; per image: "
      "encode %.2f s, encode + image part %.2f s\n",
      n, 1000 * whole_s / n, 1000 * split_s / n, whole_s / split_s,
      1000 * stopped_s / n, whole_image_s, split_image_s);
}

// Median of 5 runs of `f` in ms, printed with its ratio to `*first` (set by
// the first column).
template <typename F>
void PrintMedianMs(bool is_first, double* first, F f) {
  std::vector<double> times;
  for (int r = 0; r < 5; ++r) {
    const Stopwatch t;
    f();
    times.push_back(t.Elapsed());
  }
  std::nth_element(times.begin(), times.begin() + 2, times.end());
  const double ms = 1000.0 * times[2];
  if (is_first) *first = ms;
  std::printf(" %15.1f ms %5.2fx", ms, ms / *first);
}

// Every semantic model of the registry on each image: median of 5 runs after a
// warm-up, and the ratio to the first model (VOC DeepLabV3, the former
// default).
void BenchSemanticModels(const infer::ModelRegistry& registry,
                         const std::vector<fs::path>& images) {
  std::vector<std::string> names;
  for (const std::string& name : registry.Names()) {
    if (registry.Get(name).role == infer::ModelRole::kSemantic)
      names.push_back(name);
  }
  std::stable_partition(names.begin(), names.end(),
                        [](const std::string& n) { return n == "deeplab_v3"; });
  std::printf("\nsemantic branch, median of 5 runs (ms; ratio to %s)\n%-24s",
              names.front().c_str(), "image");
  for (const auto& n : names) std::printf(" %24s", n.c_str());
  std::printf("\n");
  std::vector<std::unique_ptr<segment::SemanticSegmenter>> models;
  for (const auto& n : names) {
    segment::SemanticSegmenterOptions o;
    o.model = n;
    models.push_back(std::make_unique<segment::SemanticSegmenter>(registry, o));
  }
  for (const fs::path& path : images) {
    const ColorImage rgb = io::ReadColorImage(path);
    std::printf("%-24s", path.stem().string().c_str());
    double first = 0.0;
    for (size_t m = 0; m < models.size(); ++m) {
      models[m]->Segment(rgb);  // warm-up
      PrintMedianMs(m == 0, &first, [&] { models[m]->Segment(rgb); });
    }
    std::printf("\n");
  }
  // Of which the logits' post-processing (softmax, upsampling to 640x480,
  // argmax): the same work on a random tensor of each model's output shape.
  std::printf("%-24s", "post-processing 640x480");
  Rng rng(1);
  double first = 0.0;
  for (size_t m = 0; m < models.size(); ++m) {
    const infer::ModelEntry& e = models[m]->entry();
    const auto& out = e.outputs.front().shape;
    infer::Tensor logits;
    logits.shape.assign(out.begin(), out.end());
    logits.data.resize(infer::Tensor::NumElements(logits.shape));
    for (float& v : logits.data) v = static_cast<float>(rng.Uniform(0, 8));
    const infer::InputTransform transform =
        infer::ComputeInputTransform(640, 480, *e.input);
    PrintMedianMs(m == 0, &first, [&] {
      segment::LogitsToLabels(logits, e.output->layout, transform,
                              e.label_offset, e.output->grid);
    });
  }
  std::printf("\n");
}

int Run(int argc, char** argv) {
  std::vector<fs::path> images;
  bool decoder_only = false;
  bool semantic_only = false;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--help") {
      std::printf(
          "bench_segment [--decoder-only|--semantic-only] [image ...]\n  "
          "Automatic mask "
          "generation vs the straightforward algorithm, the vote and the "
          "semantic branch on real images (default: Redwood + ADE20K "
          "samples); --decoder-only: per-prompt decoder timings on the first "
          "image; --semantic-only: every semantic model of the registry.\n");
      return 0;
    }
    if (std::string(argv[i]) == "--decoder-only") {
      decoder_only = true;
    } else if (std::string(argv[i]) == "--semantic-only") {
      semantic_only = true;
    } else {
      images.emplace_back(argv[i]);
    }
  }
  if (images.empty()) {
    const fs::path data =
        fs::path(SEMREC_SOURCE_DIR) / ".." / "shared" / "data";
    images = {data / "redwood_livingroom1_5" / "color" / "00000.jpg",
              data / "ade20k_val_3" / "images" / "ADE_val_00000001.jpg",
              data / "ade20k_val_3" / "images" / "ADE_val_00000002.jpg"};
  }
  const auto registry = infer::ModelRegistry::LoadDefault();
  if (semantic_only) {
    BenchSemanticModels(registry, images);
    return 0;
  }
  if (decoder_only) {
    BenchDecoder(registry, io::ReadColorImage(images.front()));
    return 0;
  }
  BenchVote();
  BenchDecoder(registry, io::ReadColorImage(images.front()));
  segment::SemanticSegmenter semantic(registry, {});

  segment::MaskGeneratorOptions fast_options;
  // Every prompt but decoded at low resolution: separates what low-resolution
  // decoding changes from what skipping prompts changes.
  segment::MaskGeneratorOptions all_low_res = fast_options;
  all_low_res.skip_covered_points = false;
  // The former default: skip covered / between-rejected points whatever the
  // image looks like there.
  segment::MaskGeneratorOptions blind_options = fast_options;
  blind_options.covered_similarity = 0.0f;
  auto fast = segment::MaskGenerator::Create(registry, fast_options);
  auto blind = segment::MaskGenerator::Create(registry, blind_options);
  auto low_res = segment::MaskGenerator::Create(registry, all_low_res);
  auto reference = segment::MaskGenerator::Create(registry, fast_options, true);

  std::printf("\n%-24s %9s | %-30s | %-30s | %-22s\n", "image", "semantic",
              "reference: s / prompts / masks", "skip without embedding test",
              "default (embedding test 0.8)");
  for (const fs::path& path : images) {
    const ColorImage rgb = io::ReadColorImage(path);
    Stopwatch t;
    semantic.Segment(rgb);
    const double semantic_s = t.Elapsed();
    t.Lap();
    const auto ref = reference->Generate(rgb);
    const double ref_s = t.Elapsed();
    t.Lap();
    const auto low = low_res->Generate(rgb);
    const double low_s = t.Elapsed();
    t.Lap();
    const auto skipped = blind->Generate(rgb);
    const double blind_s = t.Elapsed();
    t.Lap();
    const auto fst = fast->Generate(rgb);
    const double fast_s = t.Elapsed();
    std::printf(
        "%-24s %8.2fs | %6.1f s %5d %4zu | %6.1f s %5d %4zu (%.1fx) | "
        "%6.1f s %5d %4zu (%.1fx)\n",
        fmt::format("{} {}x{}", path.stem().string(), rgb.width(), rgb.height())
            .c_str(),
        semantic_s, ref_s, reference->stats().prompts_decoded, ref.size(),
        blind_s, blind->stats().prompts_decoded, skipped.size(),
        ref_s / blind_s, fast_s, fast->stats().prompts_decoded, fst.size(),
        ref_s / fast_s);
    std::printf("    %-20s %6.1f s %5d prompts %4zu masks (%.1fx)\n",
                "all prompts, low-res", low_s, low_res->stats().prompts_decoded,
                low.size(), ref_s / low_s);
    for (const auto& [name, masks] : {std::pair{"all prompts, low-res", &low},
                                      std::pair{"no embedding test", &skipped},
                                      std::pair{"default", &fst}}) {
      const Agreement a = Compare(ref, *masks);
      std::printf(
          "    %-20s vs reference: mean best IoU %.3f, recall@0.5 %.2f, "
          "recall@0.75 %.2f, precision@0.5 %.2f\n",
          name, a.mean_best_iou, a.recall_50, a.recall_75, a.precision_50);
    }
    std::printf(
        "    encode %.2f s (in each); all prompts: decode %.2f s, candidates "
        "%d, post-processing %.2f s; default: %d of %d decoded prompts "
        "stopped on the preview\n",
        fast->stats().encode_seconds, low_res->stats().decode_seconds,
        low_res->stats().candidates, low_res->stats().postprocess_seconds,
        fast->stats().prompts_rejected_early, fast->stats().prompts_decoded);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_segment: %s\n", e.what());
    return 1;
  }
}
