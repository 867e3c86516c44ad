#include "semrec/segment/semantic_segmenter.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <tbb/parallel_for.h>

#include "semrec/core/error.h"
#include "semrec/io/label_set_io.h"

namespace semrec::segment {

void SemanticSegmenterOptions::Check() const {
  CheckArgument(!model.empty(), "semantic segmenter: model name is empty");
  runtime.Check();
}

namespace {

// Bilinear sampling positions along one axis: image pixel i -> logit cells
// i0, i1 with weight t on i1 (pixel centres; align_corners = false).
struct Taps {
  std::vector<int> i0, i1;
  std::vector<float> t;
};

Taps ComputeTaps(int image_size, double scale, int input_size, int logit_size,
                 infer::GridAlignment grid) {
  Taps taps;
  taps.i0.resize(image_size);
  taps.i1.resize(image_size);
  taps.t.resize(image_size);
  const double to_logit = static_cast<double>(logit_size) / input_size;
  for (int i = 0; i < image_size; ++i) {
    // The image pixel's centre in the input frame, then in logit cells.
    const double input = (i + 0.5) * scale;
    const double cell = grid == infer::GridAlignment::kAsymmetric
                            ? (input - 0.5) * to_logit
                            : input * to_logit - 0.5;
    const double s = std::clamp(cell, 0.0, static_cast<double>(logit_size - 1));
    const int i0 = static_cast<int>(std::floor(s));
    taps.i0[i] = i0;
    taps.i1[i] = std::min(i0 + 1, logit_size - 1);
    taps.t[i] = static_cast<float>(s - i0);
  }
  return taps;
}

}  // namespace

SemanticResult LogitsToLabels(const infer::Tensor& logits,
                              infer::TensorLayout layout,
                              const infer::InputTransform& transform,
                              int label_offset, infer::GridAlignment grid) {
  CheckArgument(logits.shape.size() == 4 && logits.shape[0] == 1,
                fmt::format("semantic model: logits must have shape "
                            "[1,K,h,w] or [1,h,w,K], got [{}]",
                            fmt::join(logits.shape, ",")));
  const bool nchw = layout == infer::TensorLayout::kNCHW;
  const int k = static_cast<int>(nchw ? logits.shape[1] : logits.shape[3]);
  const int h = static_cast<int>(nchw ? logits.shape[2] : logits.shape[1]);
  const int w = static_cast<int>(nchw ? logits.shape[3] : logits.shape[2]);
  CheckArgument(k >= 1 && h >= 1 && w >= 1 &&
                    logits.data.size() == static_cast<size_t>(k) * h * w,
                "semantic model: logits tensor is empty or inconsistent");
  CheckArgument(label_offset >= 0 && k - 1 + label_offset <= 65535,
                "semantic model: labels do not fit 16 bits");

  // Class-last layout so the K values of a cell are contiguous; softmax at
  // the logits' resolution (cheap) for the confidence.
  std::vector<float> cells(logits.data.size());
  std::vector<float> probs(logits.data.size());
  tbb::parallel_for(0, h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      float* cell = &cells[(static_cast<size_t>(y) * w + x) * k];
      for (int c = 0; c < k; ++c) {
        cell[c] = nchw ? logits.data[(static_cast<size_t>(c) * h + y) * w + x]
                       : logits.data[(static_cast<size_t>(y) * w + x) * k + c];
      }
      const float max = *std::max_element(cell, cell + k);
      float sum = 0.0f;
      float* p = &probs[(static_cast<size_t>(y) * w + x) * k];
      for (int c = 0; c < k; ++c) sum += p[c] = std::exp(cell[c] - max);
      for (int c = 0; c < k; ++c) p[c] /= sum;
    }
  });

  const int width = transform.image_width, height = transform.image_height;
  const Taps tx =
      ComputeTaps(width, transform.scale_x, transform.input_width, w, grid);
  const Taps ty =
      ComputeTaps(height, transform.scale_y, transform.input_height, h, grid);
  SemanticResult result;
  result.labels = LabelMap(width, height);
  result.confidence = Image<float>(width, height);
  tbb::parallel_for(0, height, [&](int y) {
    std::vector<float> acc(k);
    const size_t r0 = static_cast<size_t>(ty.i0[y]) * w,
                 r1 = static_cast<size_t>(ty.i1[y]) * w;
    const float wy = ty.t[y];
    for (int x = 0; x < width; ++x) {
      const float wx = tx.t[x];
      const size_t cells_at[4] = {(r0 + tx.i0[x]) * k, (r0 + tx.i1[x]) * k,
                                  (r1 + tx.i0[x]) * k, (r1 + tx.i1[x]) * k};
      const float weight[4] = {(1 - wx) * (1 - wy), wx * (1 - wy),
                               (1 - wx) * wy, wx * wy};
      for (int c = 0; c < k; ++c) acc[c] = 0.0f;
      for (int n = 0; n < 4; ++n) {
        if (weight[n] == 0.0f) continue;
        const float* cell = &cells[cells_at[n]];
        for (int c = 0; c < k; ++c) acc[c] += weight[n] * cell[c];
      }
      const int best = static_cast<int>(
          std::max_element(acc.begin(), acc.end()) - acc.begin());
      float confidence = 0.0f;
      for (int n = 0; n < 4; ++n) {
        confidence += weight[n] * probs[cells_at[n] + best];
      }
      result.labels(x, y) = static_cast<uint16_t>(best + label_offset);
      result.confidence(x, y) = confidence;
    }
  });
  return result;
}

SemanticSegmenter::SemanticSegmenter(const infer::ModelRegistry& registry,
                                     const SemanticSegmenterOptions& options) {
  options.Check();
  model_ = std::make_unique<infer::OnnxModel>(registry.Get(options.model),
                                              options.runtime);
  Init();
}

SemanticSegmenter::SemanticSegmenter(const infer::ModelEntry& entry,
                                     const std::filesystem::path& file,
                                     const SemanticSegmenterOptions& options) {
  options.Check();
  model_ = std::make_unique<infer::OnnxModel>(entry, file, options.runtime);
  Init();
}

void SemanticSegmenter::Init() {
  const infer::ModelEntry& e = model_->entry();
  CheckArgument(e.role == infer::ModelRole::kSemantic && e.input && e.output,
                "model '" + e.name +
                    "' is not a semantic segmentation model (role '" +
                    infer::ModelRoleName(e.role) + "')");
  label_set_ = io::LoadLabelSet(e.label_set);
}

SemanticResult SemanticSegmenter::Segment(const ColorImage& rgb) const {
  const infer::ModelEntry& e = model_->entry();
  infer::InputTransform transform;
  infer::Tensor input = infer::ImageToTensor(rgb, *e.input, &transform);
  auto outputs = model_->Run({{e.input->name, std::move(input)}});
  auto it = outputs.find(e.output->name);
  if (it == outputs.end()) {
    throw Error("model '" + e.name + "' has no output '" + e.output->name +
                "'");
  }
  SemanticResult result = LogitsToLabels(
      it->second, e.output->layout, transform, e.label_offset, e.output->grid);
  // A channel without a class in the label set means the registry entry and
  // the model disagree; catch it here rather than writing unknown labels.
  const int channels = static_cast<int>(
      e.output->layout == infer::TensorLayout::kNCHW ? it->second.shape[1]
                                                     : it->second.shape[3]);
  if (!label_set_.Contains(static_cast<uint16_t>(e.label_offset)) ||
      !label_set_.Contains(
          static_cast<uint16_t>(channels - 1 + e.label_offset))) {
    throw Error(fmt::format(
        "model '{}' outputs {} classes (ids {}..{}), which label set '{}' does "
        "not cover",
        e.name, channels, e.label_offset, channels - 1 + e.label_offset,
        e.label_set));
  }
  return result;
}

}  // namespace semrec::segment
