#include "semrec/infer/image_input.h"

#include <gtest/gtest.h>

#include "semrec/core/error.h"

namespace semrec::infer {
namespace {

ColorImage Gradient(int w, int h) {
  ColorImage img(w, h, 3);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      img(x, y, 0) = static_cast<uint8_t>(10 + x);
      img(x, y, 1) = static_cast<uint8_t>(20 + y);
      img(x, y, 2) = 200;
    }
  }
  return img;
}

TEST(ImageInput, NhwcStretchWithoutResizeNormalisesEveryPixel) {
  ImageInputSpec spec;
  spec.layout = TensorLayout::kNHWC;
  spec.width = 8;
  spec.height = 6;
  spec.mean = {127.5f, 127.5f, 127.5f};
  spec.std = {127.5f, 127.5f, 127.5f};
  const ColorImage img = Gradient(8, 6);
  InputTransform t;
  const Tensor tensor = ImageToTensor(img, spec, &t);
  EXPECT_EQ(tensor.shape, (std::vector<int64_t>{1, 6, 8, 3}));
  EXPECT_DOUBLE_EQ(t.scale_x, 1.0);
  for (int y = 0; y < 6; ++y) {
    for (int x = 0; x < 8; ++x) {
      for (int c = 0; c < 3; ++c) {
        EXPECT_FLOAT_EQ(tensor.data[(y * 8 + x) * 3 + c],
                        img(x, y, c) / 127.5f - 1.0f);
      }
    }
  }
}

TEST(ImageInput, NchwBgrLetterboxPadsBottomRight) {
  ImageInputSpec spec;
  spec.layout = TensorLayout::kNCHW;
  spec.color = ColorOrder::kBGR;
  spec.width = 16;
  spec.height = 16;
  spec.resize = ResizePolicy::kLetterbox;
  spec.pad_value = 114;
  // 8 x 4 image -> scale 2 -> 16 x 8, rows 8..15 padded.
  const ColorImage img = Gradient(8, 4);
  InputTransform t;
  const Tensor tensor = ImageToTensor(img, spec, &t);
  EXPECT_EQ(tensor.shape, (std::vector<int64_t>{1, 3, 16, 16}));
  EXPECT_EQ(t.resized_width, 16);
  EXPECT_EQ(t.resized_height, 8);
  EXPECT_DOUBLE_EQ(t.scale_x, 2.0);
  EXPECT_DOUBLE_EQ(t.scale_y, 2.0);
  const auto at = [&](int c, int y, int x) {
    return tensor.data[(c * 16 + y) * 16 + x];
  };
  EXPECT_FLOAT_EQ(at(0, 3, 5), 200.0f);   // channel 0 = blue
  EXPECT_FLOAT_EQ(at(0, 12, 5), 114.0f);  // padding, raw
  EXPECT_FLOAT_EQ(at(2, 12, 15), 114.0f);
  // Red rises by 1 per source pixel = 0.5 per input pixel (bilinear).
  EXPECT_NEAR(at(2, 2, 9) - at(2, 2, 7), 1.0f, 1e-4);
}

TEST(ImageInput, SamStyleLongestSideWithNormalisedZeroPadding) {
  ImageInputSpec spec;
  spec.width = 1024;
  spec.height = 1024;
  spec.resize = ResizePolicy::kLetterbox;
  spec.pad_normalized = true;
  spec.mean = {123.675f, 116.28f, 103.53f};
  spec.std = {58.395f, 57.12f, 57.375f};
  const ColorImage img(640, 480, 3, 50);
  InputTransform t;
  const Tensor tensor = ImageToTensor(img, spec, &t);
  EXPECT_EQ(t.resized_width, 1024);
  EXPECT_EQ(t.resized_height, 768);
  EXPECT_DOUBLE_EQ(t.scale_x, 1.6);
  const size_t plane = 1024 * 1024;
  EXPECT_NEAR(tensor.data[plane + 100 * 1024 + 100], (50 - 116.28f) / 57.12f,
              1e-5);
  EXPECT_FLOAT_EQ(tensor.data[plane + 800 * 1024 + 100], 0.0f);
}

TEST(ImageInput, RejectsImagesThatAreNotRgb) {
  ImageInputSpec spec;
  spec.width = 4;
  spec.height = 4;
  EXPECT_THROW(ImageToTensor(ColorImage(4, 4, 1), spec), InvalidArgument);
  EXPECT_THROW(ImageToTensor(ColorImage(), spec), InvalidArgument);
}

}  // namespace
}  // namespace semrec::infer
