#include "semrec/segment/hybrid_segmenter.h"

#include <chrono>
#include <string>

#include "semrec/core/error.h"

namespace semrec::segment {

void HybridSegmenterOptions::Check() const {
  semantic.Check();
  if (use_masks) masks.Check();
}

HybridSegmenter::HybridSegmenter(const infer::ModelRegistry& registry,
                                 const HybridSegmenterOptions& options)
    : options_(options) {
  options_.Check();
  semantic_ = std::make_unique<SemanticSegmenter>(registry, options_.semantic);
  if (options_.use_masks) {
    masks_ = MaskGenerator::Create(registry, options_.masks);
  }
}

HybridResult HybridSegmenter::Segment(const ColorImage& rgb) {
  return Run(rgb, nullptr, std::nullopt);
}

SemanticResult HybridSegmenter::SegmentSemantic(const ColorImage& rgb) {
  return semantic_->Segment(rgb);
}

HybridResult HybridSegmenter::SegmentWhere(
    const ColorImage& rgb, const Image<uint8_t>& prompt_region,
    std::optional<SemanticResult> semantic) {
  CheckArgument(prompt_region.SameSize(rgb.width(), rgb.height()),
                "hybrid segmenter: the prompt region is " +
                    std::to_string(prompt_region.width()) + "x" +
                    std::to_string(prompt_region.height()) + ", the image " +
                    std::to_string(rgb.width()) + "x" +
                    std::to_string(rgb.height()));
  CheckArgument(
      !semantic || semantic->labels.SameSize(rgb.width(), rgb.height()),
      "hybrid segmenter: the semantic labels' size differs from the image's");
  return Run(rgb, &prompt_region, std::move(semantic));
}

HybridResult HybridSegmenter::Run(const ColorImage& rgb,
                                  const Image<uint8_t>* prompt_region,
                                  std::optional<SemanticResult> semantic) {
  using Clock = std::chrono::steady_clock;
  // Below this the models see a few pixels blown up to their input size and
  // return noise; say so instead.
  constexpr int kMinSide = 16;
  CheckArgument(rgb.width() >= kMinSide && rgb.height() >= kMinSide,
                "image is " + std::to_string(rgb.width()) + "x" +
                    std::to_string(rgb.height()) +
                    " pixels; segmentation needs at least 16x16");
  HybridResult result;
  const auto t0 = Clock::now();
  result.semantic_branch =
      semantic ? std::move(*semantic) : semantic_->Segment(rgb);
  const auto t1 = Clock::now();
  result.semantic_seconds = std::chrono::duration<double>(t1 - t0).count();
  if (masks_) {
    result.masks = prompt_region ? masks_->GenerateWhere(rgb, *prompt_region)
                                 : masks_->Generate(rgb);
    result.mask_stats = masks_->stats();
  }
  const auto t2 = Clock::now();
  result.vote = Vote(result.semantic_branch.labels, result.masks);
  result.vote_seconds =
      std::chrono::duration<double>(Clock::now() - t2).count();
  return result;
}

}  // namespace semrec::segment
