#include "semrec/segment/mask_generator.h"

#include <gtest/gtest.h>

#include "semrec/core/error.h"

namespace semrec::segment {
namespace {

Mask RectMask(int w, int h, Box box, float iou = 0.9f) {
  Image<uint8_t> img(w, h);
  for (int y = box.y0; y < box.y1; ++y) {
    for (int x = box.x0; x < box.x1; ++x) img(x, y) = 1;
  }
  Mask m = MaskFromImage(img);
  m.predicted_iou = iou;
  return m;
}

TEST(MaskGenerator, StabilityScoreIsTheIouOfTheOffsetThresholds) {
  // Values: 3 above +1, 2 in (-1, 1], 1 below: 3 / 5.
  EXPECT_FLOAT_EQ(StabilityScore({2.0f, 1.5f, 5.0f, 0.5f, -0.5f, -3.0f}, 0, 1),
                  3.0f / 5.0f);
  EXPECT_FLOAT_EQ(StabilityScore({-5.0f, -2.0f}, 0, 1), 1.0f);
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
  o.model.backend = "sam3";
  EXPECT_THROW(o.Check(), InvalidArgument);
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
