#include "semrec/detect/yolox_detector.h"

#include <cmath>

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/io/image_io.h"
#include "semrec/testing/test_util.h"

namespace semrec::detect {
namespace {

infer::InputTransform Letterbox416(int w, int h) {
  infer::ImageInputSpec spec;
  spec.width = spec.height = 416;
  spec.resize = infer::ResizePolicy::kLetterbox;
  return infer::ComputeInputTransform(w, h, spec);
}

// Raw output with every score 0 except the anchors set by Set().
struct Raw {
  infer::Tensor t{{1, 3549, 85}, std::vector<float>(3549 * 85, 0.0f)};
  // Anchor index of grid cell (gx, gy) at stride s.
  static int Anchor(int s, int gx, int gy) {
    int base = 0;
    for (int stride : {8, 16}) {
      if (stride == s) break;
      base += (416 / stride) * (416 / stride);
    }
    return base + gy * (416 / s) + gx;
  }
  void Set(int s, int gx, int gy, float dx, float dy, float w_cells,
           float h_cells, float obj, int cls, float cls_score) {
    float* p = &t.data[static_cast<size_t>(Anchor(s, gx, gy)) * 85];
    p[0] = dx;
    p[1] = dy;
    p[2] = std::log(w_cells);
    p[3] = std::log(h_cells);
    p[4] = obj;
    p[5 + cls] = cls_score;
  }
};

TEST(Yolox, DecodesGridRelativeBoxesThroughTheLetterbox) {
  Raw raw;
  // Person at stride 8, cell (10, 20): centre (84, 164), 32 x 64 in the 416
  // frame; score 0.9 * 0.8.
  raw.Set(8, 10, 20, 0.5f, 0.5f, 4, 8, 0.9f, 0, 0.8f);
  // Its neighbour, overlapping, weaker: removed by NMS.
  raw.Set(8, 11, 20, 0.5f, 0.5f, 4, 8, 0.9f, 0, 0.6f);
  // A car (class 2) at stride 32 and a faint person: filtered out.
  raw.Set(32, 3, 3, 0.5f, 0.5f, 2, 2, 0.95f, 2, 0.95f);
  raw.Set(16, 5, 5, 0.5f, 0.5f, 2, 2, 0.3f, 0, 0.5f);
  YoloxOptions options;
  // An 832 x 624 image: letterbox scale 0.5.
  const auto dets = DecodeYolox(raw.t, Letterbox416(832, 624), options, 1);
  ASSERT_EQ(dets.size(), 1u);
  EXPECT_EQ(dets[0].class_id, 1);
  EXPECT_NEAR(dets[0].score, 0.72, 1e-6);
  EXPECT_NEAR(dets[0].box.left, (84 - 16) * 2.0, 1e-3);
  EXPECT_NEAR(dets[0].box.top, (164 - 32) * 2.0, 1e-3);
  EXPECT_NEAR(dets[0].box.width, 64.0, 1e-3);
  EXPECT_NEAR(dets[0].box.height, 128.0, 1e-3);
  // All classes: the car appears too (COCO id 3), first by score.
  options.classes.clear();
  const auto all = DecodeYolox(raw.t, Letterbox416(832, 624), options, 1);
  ASSERT_EQ(all.size(), 2u);
  EXPECT_EQ(all[0].class_id, 3);
  EXPECT_NEAR(all[0].box.left, ((3 + 0.5) * 32 - 32) * 2.0, 1e-3);
}

TEST(Yolox, RejectsOutputsThatDoNotMatchTheInput) {
  const infer::Tensor wrong{{1, 100, 85}, std::vector<float>(100 * 85)};
  EXPECT_THROW(DecodeYolox(wrong, Letterbox416(640, 480), {}, 1),
               InvalidArgument);
  YoloxOptions bad;
  bad.nms_iou = 0;
  EXPECT_THROW(bad.Check(), InvalidArgument);
}

TEST(Yolox, RealModelFindsVehiclesInAStreetAndNothingInABlankImage) {
  if (!std::filesystem::exists(semrec::testing::ModelDir() /
                               "yolox_nano.onnx")) {
    SEMREC_SKIP("yolox_nano.onnx not installed: run scripts/setup");
  }
  SEMREC_REQUIRE_SAMPLE_DATA(ade, "ade20k_val_3");
  YoloxOptions options;
  options.classes.clear();
  options.runtime.model_dir = semrec::testing::ModelDir();
  const YoloxDetector detector(infer::ModelRegistry::LoadDefault(), options);
  const ColorImage street =
      io::ReadColorImage(ade / "images" / "ADE_val_00000003.jpg");
  const auto dets = detector.Detect(street);
  ASSERT_FALSE(dets.empty());
  int vehicles = 0;
  for (const auto& d : dets) {
    const Box& b = d.box;
    EXPECT_GT(b.width, 0);
    EXPECT_GT(b.left + b.width, 0);
    EXPECT_LT(b.left, street.width());
    // COCO: 3 car, 6 bus, 8 truck.
    vehicles += d.class_id == 3 || d.class_id == 6 || d.class_id == 8;
  }
  EXPECT_GT(vehicles, 0);
  EXPECT_TRUE(detector.Detect(ColorImage(640, 480, 3, 128)).empty());
}

}  // namespace
}  // namespace semrec::detect
