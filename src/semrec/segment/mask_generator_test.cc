#include "semrec/segment/mask_generator.h"

#include <algorithm>
#include <vector>

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/testing/masks.h"

namespace semrec::segment {
namespace {

using testing::RectMask;

TEST(MaskGenerator, StabilityScoreIsTheIouOfTheOffsetThresholds) {
  // Values: 3 above +1, 2 in (-1, 1], 1 below: 3 / 5.
  EXPECT_FLOAT_EQ(StabilityScore({2.0f, 1.5f, 5.0f, 0.5f, -0.5f, -3.0f}, 0, 1),
                  3.0f / 5.0f);
  EXPECT_FLOAT_EQ(StabilityScore({-5.0f, -2.0f}, 0, 1), 1.0f);
}

// A 640 x 480 image letterboxed into SAM's 1024 x 1024 frame: the image
// covers preview rows 0..47 of 64 (low-res cell 4y + 2 < 192).
infer::InputTransform SamFrame() {
  infer::InputTransform t;
  t.image_width = 640;
  t.image_height = 480;
  t.input_width = t.input_height = 1024;
  t.resized_width = 1024;
  t.resized_height = 768;
  t.scale_x = t.scale_y = 1.6;
  return t;
}

// A 64 x 64 preview: `stable` cells at +5, `band` cells at 0 (inside the
// +-1 band), in rows from `row` on, the rest at -5.
LowResMask Preview(int stable, int band, int row = 0) {
  LowResMask p;
  p.width = p.height = 64;
  p.logits.assign(64 * 64, -5.0f);
  for (int i = 0; i < stable + band; ++i) {
    p.logits[static_cast<size_t>(row) * 64 + i] = i < stable ? 5.0f : 0.0f;
  }
  return p;
}

TEST(MaskGenerator, PreviewRejectsOnlyMasksClearlyBelowTheFilters) {
  MaskFilter filter;
  filter.min_predicted_iou = 0.88f;
  filter.min_stability = 0.95f;
  const auto t = SamFrame();
  // 400 cells, estimate 0.80; the margin at n = 400 is 0.03 + 0.025.
  EXPECT_FALSE(MaskPreviewMayPass(Preview(320, 80), 0.9f, filter, t));
  // 0.92 is within the margin: decode it fully.
  EXPECT_TRUE(MaskPreviewMayPass(Preview(368, 32), 0.9f, filter, t));
  EXPECT_TRUE(MaskPreviewMayPass(Preview(400, 0), 0.9f, filter, t));
  // The predicted IoU decides alone.
  EXPECT_FALSE(MaskPreviewMayPass(Preview(400, 0), 0.8f, filter, t));
  // Too few cells to tell (10, estimate 0.5).
  EXPECT_TRUE(MaskPreviewMayPass(Preview(5, 5), 0.9f, filter, t));
  // Unstable cells in the letterbox padding (rows >= 48) do not count.
  LowResMask padded = Preview(400, 0);
  for (int i = 0; i < 300; ++i) padded.logits[50 * 64 + i] = 0.0f;
  EXPECT_TRUE(MaskPreviewMayPass(padded, 0.9f, filter, t));
  EXPECT_FALSE(MaskPreviewMayPass(Preview(100, 300, 40), 0.9f, filter, t));
}

// mask_margin_logits: the tokens near a mask's edge are upscaled, the others
// keep their preview logit. A 6 x 6 token grid, logits +10 inside a 2 x 2
// square (tokens (2..3, 2..3)), -10 outside, and one token at -0.5.
TEST(MaskGenerator, OnlyTokensNearTheMasksEdgeAreUpscaled) {
  LowResMask preview;
  preview.width = preview.height = 6;
  preview.logits.assign(36, -10.0f);
  for (int y = 2; y <= 3; ++y) {
    for (int x = 2; x <= 3; ++x) preview.logits[y * 6 + x] = 10.0f;
  }
  // Sign changes: the square and its ring (4 x 4 tokens from (1, 1)).
  std::vector<int64_t> ring;
  for (int y = 1; y <= 4; ++y) {
    for (int x = 1; x <= 4; ++x) ring.push_back(y * 6 + x);
  }
  EXPECT_EQ(TokensNearMaskEdge(preview, 4.0f), ring);
  // A logit under the margin makes its neighbours near the edge too.
  preview.logits[0] = -0.5f;
  std::vector<int64_t> with_corner = {0, 1, 6, 7};
  for (int64_t t : ring) {
    if (t != 7) with_corner.push_back(t);
  }
  std::sort(with_corner.begin(), with_corner.end());
  EXPECT_EQ(TokensNearMaskEdge(preview, 4.0f), with_corner);
  EXPECT_EQ(TokensNearMaskEdge(preview, 0.4f), ring);
  EXPECT_EQ(TokensNearMaskEdge(preview, 20.0f).size(), 36u);

  // Blocks of a 24 x 24 low-res mask, cell value = 100 row + col; token t's
  // 16 values in the order (ky1, kx1, ky2, kx2).
  auto block = [](int64_t t) {
    std::vector<float> b;
    for (int c = 0; c < 16; ++c) {
      const int64_t row = 4 * (t / 6) + 2 * ((c >> 3) & 1) + ((c >> 1) & 1);
      const int64_t col = 4 * (t % 6) + 2 * ((c >> 2) & 1) + (c & 1);
      b.push_back(static_cast<float>(100 * row + col));
    }
    return b;
  };
  std::vector<float> blocks;
  for (int64_t t : ring) {
    const std::vector<float> b = block(t);
    blocks.insert(blocks.end(), b.begin(), b.end());
  }
  const LowResMask m = ComposeMaskBlocks(preview, ring, blocks);
  ASSERT_EQ(m.width, 24);
  ASSERT_EQ(m.height, 24);
  for (int row = 0; row < 24; ++row) {
    for (int col = 0; col < 24; ++col) {
      const int64_t t = (row / 4) * 6 + col / 4;
      const bool upscaled = std::count(ring.begin(), ring.end(), t) > 0;
      EXPECT_EQ(m.logits[row * 24 + col],
                upscaled ? static_cast<float>(100 * row + col)
                         : preview.logits[static_cast<size_t>(t)])
          << row << "," << col;
    }
  }
  EXPECT_THROW(ComposeMaskBlocks(preview, ring, {1.0f}), InvalidArgument);
  EXPECT_THROW(ComposeMaskBlocks(preview, {36}, block(0)), InvalidArgument);
  PromptableOptions bad;
  bad.mask_margin_logits = -1.0f;
  EXPECT_THROW(bad.Check(), InvalidArgument);
}

TEST(MaskGenerator, BoxNmsKeepsTheBestScoredOfOverlappingMasks) {
  std::vector<Mask> masks = {RectMask(50, 50, {0, 0, 20, 20}, 0.90f),
                             RectMask(50, 50, {1, 1, 21, 21}, 0.95f),
                             RectMask(50, 50, {30, 30, 40, 40}, 0.89f),
                             RectMask(50, 50, {0, 0, 20, 40}, 0.91f)};
  const auto kept = BoxNms(masks, 0.7f);
  ASSERT_EQ(kept.size(), 3u);
  EXPECT_FLOAT_EQ(kept[0].predicted_iou, 0.95f);  // beat the 0.90 twin
  EXPECT_FLOAT_EQ(kept[1].predicted_iou, 0.91f);  // IoU 0.45 with it: kept
  EXPECT_FLOAT_EQ(kept[2].predicted_iou, 0.89f);
}

TEST(MaskGenerator, SmallIslandsAndHolesAreRemoved) {
  Image<uint8_t> img(60, 40);
  for (int y = 5; y < 35; ++y) {
    for (int x = 5; x < 35; ++x) img(x, y) = 1;
  }
  for (int y = 10; y < 13; ++y) {
    for (int x = 10; x < 13; ++x) img(x, y) = 0;  // 9 px hole
  }
  for (int y = 5; y < 8; ++y) {
    for (int x = 50; x < 53; ++x) img(x, y) = 1;  // 9 px island
  }
  Mask m = MaskFromImage(img);
  EXPECT_EQ(m.area, 900 - 9 + 9);
  RemoveSmallRegions(&m, 20);
  EXPECT_EQ(m.area, 900);
  EXPECT_TRUE(m.Contains(11, 11));
  EXPECT_FALSE(m.Contains(51, 6));
  EXPECT_EQ(m.box.x1, 35);
  // A mask made only of small pieces keeps its largest piece.
  Image<uint8_t> bits(20, 20);
  bits(1, 1) = 1;
  bits(10, 10) = bits(11, 10) = 1;
  Mask tiny = MaskFromImage(bits);
  RemoveSmallRegions(&tiny, 100);
  EXPECT_EQ(tiny.area, 2);
}

TEST(MaskGenerator, OptionsAreChecked) {
  MaskGeneratorOptions o;
  EXPECT_NO_THROW(o.Check());
  o.points_per_side = 0;
  EXPECT_THROW(o.Check(), InvalidArgument);
  o = {};
  EXPECT_THROW(infer::ParseMaskBackend("sam3"), InvalidArgument);
  EXPECT_EQ(infer::ParseMaskBackend("sam2"), infer::MaskBackend::kSam2);
  using Kernel = PromptableOptions::Kernel;
  for (const Kernel k :
       {Kernel::kAuto, Kernel::kOn, Kernel::kBf16, Kernel::kOff}) {
    EXPECT_EQ(PromptableOptions::ParseKernel(PromptableOptions::KernelName(k)),
              k);
  }
  EXPECT_THROW(PromptableOptions::ParseKernel("fast"), InvalidArgument);
  o = {};
  o.box_nms_threshold = 0;
  EXPECT_THROW(o.Check(), InvalidArgument);
  o = {};
  o.crop_layers = -1;
  EXPECT_THROW(o.Check(), InvalidArgument);
  o = {};
  o.dense_stride = 3;
  EXPECT_THROW(o.Check(), InvalidArgument);
}

}  // namespace
}  // namespace semrec::segment
