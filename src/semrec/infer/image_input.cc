#include "semrec/infer/image_input.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "semrec/core/error.h"

namespace semrec::infer {

InputTransform ComputeInputTransform(int image_width, int image_height,
                                     const ImageInputSpec& spec) {
  CheckArgument(image_width > 0 && image_height > 0,
                "model input: the image is empty");
  CheckArgument(spec.width > 0 && spec.height > 0,
                "model input: the input size must be > 0");
  InputTransform t;
  t.image_width = image_width;
  t.image_height = image_height;
  t.input_width = spec.width;
  t.input_height = spec.height;
  if (spec.resize == ResizePolicy::kStretch) {
    t.resized_width = spec.width;
    t.resized_height = spec.height;
  } else {
    const double scale =
        std::min(static_cast<double>(spec.width) / image_width,
                 static_cast<double>(spec.height) / image_height);
    t.resized_width = std::clamp(
        static_cast<int>(std::lround(image_width * scale)), 1, spec.width);
    t.resized_height = std::clamp(
        static_cast<int>(std::lround(image_height * scale)), 1, spec.height);
  }
  t.scale_x = static_cast<double>(t.resized_width) / image_width;
  t.scale_y = static_cast<double>(t.resized_height) / image_height;
  return t;
}

Tensor ImageToTensor(const ColorImage& rgb, const ImageInputSpec& spec,
                     InputTransform* transform) {
  CheckArgument(rgb.channels() == 3,
                "model input: expected an RGB image with 3 channels, got " +
                    std::to_string(rgb.channels()));
  const InputTransform t =
      ComputeInputTransform(rgb.width(), rgb.height(), spec);
  if (transform) *transform = t;

  const cv::Mat src(rgb.height(), rgb.width(), CV_8UC3,
                    const_cast<uint8_t*>(rgb.data()));
  cv::Mat resized;
  if (t.resized_width == rgb.width() && t.resized_height == rgb.height()) {
    resized = src;
  } else {
    // INTER_AREA when shrinking a lot avoids aliasing; bilinear otherwise
    // (what the models' reference pre-processing does).
    const bool shrink = t.scale_x < 0.5 && t.scale_y < 0.5;
    cv::resize(src, resized, cv::Size(t.resized_width, t.resized_height), 0, 0,
               shrink ? cv::INTER_AREA : cv::INTER_LINEAR);
  }

  const int w = spec.width, h = spec.height;
  Tensor tensor;
  tensor.shape = spec.layout == TensorLayout::kNCHW
                     ? std::vector<int64_t>{1, 3, h, w}
                     : std::vector<int64_t>{1, h, w, 3};
  tensor.data.assign(static_cast<size_t>(w) * h * 3, 0.0f);
  std::array<float, 3> pad;
  std::array<float, 3> inv_std;
  for (int c = 0; c < 3; ++c) {
    inv_std[c] = 1.0f / spec.std[c];
    pad[c] = spec.pad_normalized ? 0.0f
                                 : (spec.pad_value - spec.mean[c]) * inv_std[c];
  }
  const bool bgr = spec.color == ColorOrder::kBGR;
  const bool nchw = spec.layout == TensorLayout::kNCHW;
  const size_t plane = static_cast<size_t>(w) * h;
  for (int y = 0; y < h; ++y) {
    const uint8_t* row =
        y < t.resized_height ? resized.ptr<uint8_t>(y) : nullptr;
    for (int x = 0; x < w; ++x) {
      const bool inside = row && x < t.resized_width;
      for (int c = 0; c < 3; ++c) {
        float v = pad[c];
        if (inside) {
          const int src_c = bgr ? 2 - c : c;
          v = (static_cast<float>(row[3 * x + src_c]) - spec.mean[c]) *
              inv_std[c];
        }
        const size_t i = static_cast<size_t>(y) * w + x;
        tensor.data[nchw ? c * plane + i : 3 * i + c] = v;
      }
    }
  }
  return tensor;
}

}  // namespace semrec::infer
