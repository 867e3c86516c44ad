#include "semrec/segment/semantic_segmenter.h"

#include <opencv2/imgproc.hpp>

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/core/random.h"
#include "semrec/testing/test_util.h"

namespace semrec::segment {
namespace {

infer::InputTransform Stretch(int image_w, int image_h, int input_w,
                              int input_h) {
  infer::ImageInputSpec spec;
  spec.width = input_w;
  spec.height = input_h;
  return infer::ComputeInputTransform(image_w, image_h, spec);
}

// Reference: OpenCV's bilinear resize (half-pixel centres, clamped borders)
// of every channel, then argmax.
LabelMap ReferenceLabels(const infer::Tensor& nchw, int out_w, int out_h) {
  const int k = static_cast<int>(nchw.shape[1]),
            h = static_cast<int>(nchw.shape[2]),
            w = static_cast<int>(nchw.shape[3]);
  std::vector<cv::Mat> up(k);
  for (int c = 0; c < k; ++c) {
    const cv::Mat plane(
        h, w, CV_32F,
        const_cast<float*>(&nchw.data[static_cast<size_t>(c) * h * w]));
    cv::resize(plane, up[c], cv::Size(out_w, out_h), 0, 0, cv::INTER_LINEAR);
  }
  LabelMap labels(out_w, out_h);
  for (int y = 0; y < out_h; ++y) {
    for (int x = 0; x < out_w; ++x) {
      int best = 0;
      for (int c = 1; c < k; ++c) {
        if (up[c].at<float>(y, x) > up[best].at<float>(y, x)) best = c;
      }
      labels(x, y) = static_cast<uint16_t>(best);
    }
  }
  return labels;
}

TEST(LogitsToLabels, MatchesOpenCvBilinearUpsamplingThenArgmax) {
  Rng rng(3);
  infer::Tensor logits{{1, 5, 12, 16}, {}};
  for (int i = 0; i < 5 * 12 * 16; ++i)
    logits.data.push_back(static_cast<float>(rng.Uniform(-3, 3)));
  // Logits at 1/4 of a 64 x 48 input frame, image 128 x 96 (stretch).
  const SemanticResult r = LogitsToLabels(logits, infer::TensorLayout::kNCHW,
                                          Stretch(128, 96, 64, 48), 0);
  const LabelMap ref = ReferenceLabels(logits, 128, 96);
  int64_t differ = 0;
  for (size_t i = 0; i < ref.NumPixels(); ++i) {
    differ += r.labels.values()[i] != ref.values()[i];
  }
  // Float rounding may flip near-ties only.
  EXPECT_LE(differ, 3) << "of " << ref.NumPixels();
  // The confidence is the chosen class's softmax probability interpolated
  // from the logits' grid: a probability, and on average above chance (1/K).
  double sum = 0;
  for (float c : r.confidence.values()) {
    EXPECT_GE(c, 0.0f);
    EXPECT_LE(c, 1.0f + 1e-6f);
    sum += c;
  }
  EXPECT_GT(sum / r.confidence.NumPixels(), 0.3);
}

TEST(LogitsToLabels, NhwcEqualsNchwAndOffsetShiftsIds) {
  Rng rng(4);
  const int k = 4, h = 6, w = 5;
  infer::Tensor nchw{{1, k, h, w}, std::vector<float>(k * h * w)};
  infer::Tensor nhwc{{1, h, w, k}, std::vector<float>(k * h * w)};
  for (int c = 0; c < k; ++c) {
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const float v = static_cast<float>(rng.Uniform(-1, 1));
        nchw.data[(c * h + y) * w + x] = v;
        nhwc.data[(y * w + x) * k + c] = v;
      }
    }
  }
  const auto t = Stretch(20, 24, 5, 6);
  const auto a = LogitsToLabels(nchw, infer::TensorLayout::kNCHW, t, 0);
  const auto b = LogitsToLabels(nhwc, infer::TensorLayout::kNHWC, t, 1);
  for (size_t i = 0; i < a.labels.NumPixels(); ++i) {
    EXPECT_EQ(b.labels.values()[i], a.labels.values()[i] + 1);
  }
}

TEST(LogitsToLabels, LetterboxedFramesUseOnlyTheImagePart) {
  // Input 8 x 8, image 8 x 4 letterboxed into the top half. Logits: class 1
  // in the top half, class 2 (the padding) below: the image must be all 1.
  infer::ImageInputSpec spec;
  spec.width = 8;
  spec.height = 8;
  spec.resize = infer::ResizePolicy::kLetterbox;
  const auto t = infer::ComputeInputTransform(8, 4, spec);
  infer::Tensor logits{{1, 3, 8, 8}, std::vector<float>(3 * 64, 0.0f)};
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x < 8; ++x)
      logits.data[(y < 4 ? 1 : 2) * 64 + y * 8 + x] = 5;
  }
  const auto r = LogitsToLabels(logits, infer::TensorLayout::kNCHW, t, 0);
  for (uint16_t v : r.labels.values()) EXPECT_EQ(v, 1);
}

TEST(LogitsToLabels, CoarseGridsSampleWhereTheirExportSays) {
  // 16 px wide input, 4 logit cells (stride 4): class 1's logit is the cell
  // index, class 0's is 1.5, so class 1 wins where the sampled cell > 1.5.
  // Half-pixel centres: cell = (x + 0.5) / 4 - 0.5 -> from x = 8. TFLite's
  // asymmetric resize: cell = x / 4 -> from x = 7.
  const auto t = Stretch(16, 1, 16, 1);
  infer::Tensor logits{{1, 2, 1, 4}, {1.5f, 1.5f, 1.5f, 1.5f, 0, 1, 2, 3}};
  const auto half = LogitsToLabels(logits, infer::TensorLayout::kNCHW, t, 0);
  const auto asym = LogitsToLabels(logits, infer::TensorLayout::kNCHW, t, 0,
                                   infer::GridAlignment::kAsymmetric);
  for (int x = 0; x < 16; ++x) {
    EXPECT_EQ(half.labels(x, 0), x >= 8 ? 1 : 0) << x;
    EXPECT_EQ(asym.labels(x, 0), x >= 7 ? 1 : 0) << x;
  }
}

TEST(LogitsToLabels, RejectsMalformedLogits) {
  const auto t = Stretch(4, 4, 4, 4);
  EXPECT_THROW(LogitsToLabels(infer::Tensor{{1, 2, 4}, std::vector<float>(8)},
                              infer::TensorLayout::kNCHW, t, 0),
               InvalidArgument);
  EXPECT_THROW(
      LogitsToLabels(infer::Tensor{{1, 2, 4, 4}, std::vector<float>(7)},
                     infer::TensorLayout::kNCHW, t, 0),
      InvalidArgument);
}

}  // namespace
}  // namespace semrec::segment
