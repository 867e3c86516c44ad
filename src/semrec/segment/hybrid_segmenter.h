// The hybrid segmenter: semantic branch + mask branch + vote.
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include "semrec/segment/mask_generator.h"
#include "semrec/segment/semantic_segmenter.h"
#include "semrec/segment/vote.h"

namespace semrec::segment {

struct HybridSegmenterOptions {
  SemanticSegmenterOptions semantic;
  /// Without masks the result is the semantic branch alone (instance map all
  /// 0).
  bool use_masks = true;
  MaskGeneratorOptions masks;
  void Check() const;
};

struct HybridResult {
  /// The semantic branch's own output.
  SemanticResult semantic_branch;
  /// Masks (largest first) with their voted classes in `vote.mask_labels`.
  std::vector<Mask> masks;
  /// Final semantic and instance maps.
  VoteResult vote;
  MaskGeneratorStats mask_stats;
  double semantic_seconds = 0;
  double vote_seconds = 0;
};

class HybridSegmenter {
 public:
  HybridSegmenter(const infer::ModelRegistry& registry,
                  const HybridSegmenterOptions& options);
  HybridResult Segment(const ColorImage& rgb);
  /// The semantic branch alone (map guidance looks at its labels before it
  /// chooses where to prompt).
  SemanticResult SegmentSemantic(const ColorImage& rgb);
  /// Segment() with mask prompts only where `prompt_region` is non-zero (map
  /// guidance: where the map cannot explain the frame); the semantic branch
  /// still sees the whole image (or its given result, from SegmentSemantic),
  /// so pixels outside every mask keep its label. Throws InvalidArgument when
  /// the region's or the given labels' size differs from the image's.
  HybridResult SegmentWhere(
      const ColorImage& rgb, const Image<uint8_t>& prompt_region,
      std::optional<SemanticResult> semantic = std::nullopt);
  const LabelSet& label_set() const { return semantic_->label_set(); }

 private:
  HybridResult Run(const ColorImage& rgb, const Image<uint8_t>* prompt_region,
                   std::optional<SemanticResult> semantic);

  HybridSegmenterOptions options_;
  std::unique_ptr<SemanticSegmenter> semantic_;
  std::unique_ptr<MaskGenerator> masks_;
};

}  // namespace semrec::segment
