// The mask branch: automatic mask generation (SAM's "segment everything")
// over a promptable model, plus the straightforward reference
// implementation the fast one is measured against.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "semrec/core/image.h"
#include "semrec/infer/model_registry.h"
#include "semrec/segment/mask.h"
#include "semrec/segment/promptable.h"

namespace semrec::segment {

struct MaskGeneratorOptions {
  /// The promptable model (SAM or SAM2 backend, registry names, threads).
  PromptableOptions model;
  /// Point prompts on a points_per_side x points_per_side grid (SAM: 32).
  int points_per_side = 32;
  /// Keep masks whose predicted IoU >= this (SAM: 0.88).
  float pred_iou_threshold = 0.88f;
  /// Stability score = IoU of the masks thresholded at +offset and -offset
  /// (at image resolution, as SAM; see PromptableSegmenter::StabilityScore);
  /// keep >= this (SAM: 0.95, offset 1.0).
  float stability_threshold = 0.95f;
  float stability_offset = 1.0f;
  /// Box NMS between kept masks, highest predicted IoU first (SAM: 0.7).
  float box_nms_threshold = 0.7f;
  /// Remove disconnected regions and fill holes smaller than this many pixels
  /// (SAM's min_mask_region_area, off there by default; 100 px here removes
  /// the speckle that upsampling 256x256 logits leaves at 640x480).
  int min_region_area_px = 100;
  /// Skip a grid point when an already accepted mask covers it: most of the
  /// 1024 prompts land on objects that are already segmented, and their
  /// masks would be removed by NMS anyway. The speed lever (see bench/).
  bool skip_covered_points = true;
  /// Points of the coarser grid with this stride (every dense_stride-th row
  /// and column, decoded first) are never skipped, so masks nested in larger
  /// ones (a sofa in a room) are still found; each finer level (stride / 2,
  /// ..., 1) is skipped where covered or between rejected points of the level
  /// above. 1 = no skipping at all; must be a power of 2. 4 (was 2): 1.19x
  /// faster full frames, 99% of stride 2's instances (>= 1000 px) at IoU >=
  /// 0.8, 99.8% of pixels voted alike, ADE20K mIoU unchanged
  /// (bench/bench_prompts).
  int dense_stride = 4;
  /// Also skip a finer point when every dense point around it produced a
  /// rejected mask: SAM's quality varies smoothly, so such a point mostly
  /// yields another rejected mask.
  bool skip_between_rejected = true;
  /// Skip only where the image looks alike: a covered finer point is decoded
  /// anyway when the image embedding there has cosine similarity below this
  /// to the covering mask's mean embedding (a mask nested in an accepted one,
  /// a cushion on a sofa, starts where the embedding changes); for points
  /// between rejected ones see rejected_similarity. 0 = skip regardless (the
  /// former default: ~2x faster, but it missed 23-43% of the straightforward
  /// result's masks). 0.8 found 91-100% of them on 7 test images at 8.4-12.3 s
  /// per image (bench/bench_segment); 0.6 is 1.28x faster than 0.8
  /// at 99% of 0.8's instances and 99.9% of its pixels voted alike, ADE20K
  /// mIoU 48.1 -> 49.7 (bench/bench_prompts).
  float covered_similarity = 0.6f;
  /// The same test for a point between rejected ones: skipped when its
  /// embedding is at least this similar to each of theirs.
  float rejected_similarity = 0.8f;
  /// A point between rejected ones is also skipped where, for each of them,
  /// it lies inside its rejected mask (the mask's logit there above
  /// rejected_inside_logit; the preview's when rejected on it) and the image
  /// there is at least rejected_inside_similarity like at its point (or
  /// rejected_similarity like anywhere): prompted inside a mask SAM found
  /// unstable, it mostly gives that mask again. A neighbour skipped itself
  /// (no mask) never counts as inside. Off: rejected_inside_similarity = 1.
  /// 0.5 / 2: 12% fewer prompts per full frame, the same
  /// instances and pixels as without it on bench_prompts' 5 frames and 8
  /// others; 0.6 / 0 loses chess frame 50's floor (bench/bench_prompts).
  float rejected_inside_similarity = 0.5f;
  float rejected_inside_logit = 2.0f;
  /// SAM's crop layers (off by default, as in SAM): layer l adds a 2^l x 2^l
  /// grid of overlapping crops, each encoded and prompted with
  /// points_per_side / crop_points_downscale^l points per side; masks cut by
  /// a crop edge are dropped and NMS across crops prefers smaller crops.
  int crop_layers = 0;
  float crop_overlap_ratio = 512.0f / 1500.0f;
  int crop_points_downscale = 1;
  /// Prompts decoded in parallel before the covered set is updated. Fixed
  /// (not the core count) so results do not depend on the machine.
  int prompts_per_wave = 8;
  void Check() const;
  /// The predicted-IoU and stability thresholds above, for
  /// PromptableSegmenter::DecodeUnlessRejected.
  MaskFilter Filter() const;
};

struct MaskGeneratorStats {
  int prompts_total = 0;
  int prompts_decoded = 0;
  /// Of those, stopped on their mask's preview (the mask upscaling skipped;
  /// PromptableSegmenter::DecodeUnlessRejected).
  int prompts_rejected_early = 0;
  int candidates = 0;  // passed the IoU and stability filters
  int kept = 0;        // after NMS and clean-up
  /// Image encoder runs (one per crop that had prompts).
  int encoder_calls = 0;
  double encode_seconds = 0;
  double decode_seconds = 0;
  double postprocess_seconds = 0;
};

class MaskGenerator {
 public:
  virtual ~MaskGenerator() = default;
  /// SAM / SAM2 backends (options.model.backend) or the reference (the
  /// straightforward algorithm: every prompt, full-resolution masks, the
  /// decoder export unsplit).
  static std::unique_ptr<MaskGenerator> Create(
      const infer::ModelRegistry& registry, const MaskGeneratorOptions& options,
      bool reference = false);

  /// Masks of `rgb`, sorted by area (largest first), non-empty, each with its
  /// predicted IoU, stability and prompt point.
  virtual std::vector<Mask> Generate(const ColorImage& rgb) = 0;
  /// As Generate, with grid prompts only where `prompt_region` (same size as
  /// `rgb`) is non-zero: map-guided segmentation prompts only where the map
  /// cannot explain the frame. A region without any grid point returns no masks
  /// without running the encoder. Throws InvalidArgument for a region of
  /// another size.
  virtual std::vector<Mask> GenerateWhere(
      const ColorImage& rgb, const Image<uint8_t>& prompt_region) = 0;
  virtual const MaskGeneratorStats& stats() const = 0;
  /// Makes model() hold `rgb`'s encoding for further prompts (object
  /// detections' boxes): free when the last Generate() / GenerateWhere()
  /// encoded this same image whole (no crops; compared by content), else one
  /// encoder run, counted in stats().encoder_calls / encode_seconds.
  virtual void EncodeUnlessCurrent(const ColorImage& rgb) = 0;
  /// The underlying promptable model (for box prompts, embeddings).
  virtual PromptableSegmenter& model() = 0;
};

}  // namespace semrec::segment
