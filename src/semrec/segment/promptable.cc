#include "semrec/segment/promptable.h"

#include <algorithm>
#include <cmath>

#include "semrec/core/enum_names.h"
#include "semrec/core/error.h"

namespace semrec::segment {

PromptableOptions PromptableOptions::FromRegistry(
    const infer::ModelRegistry& registry, const std::string& prefix,
    const infer::OnnxModelOptions& runtime) {
  PromptableOptions o;
  o.encoder = prefix + "_encoder";
  o.decoder = prefix + "_decoder";
  o.backend = registry.Get(o.decoder).backend;
  o.runtime = runtime;
  return o;
}

std::vector<int64_t> TokensNearMaskEdge(const LowResMask& preview,
                                        float margin) {
  const int w = preview.width, h = preview.height;
  CheckArgument(
      w > 0 && h > 0 && preview.logits.size() == static_cast<size_t>(w) * h,
      "TokensNearMaskEdge: preview size and logits disagree");
  auto at = [&](int x, int y) {
    return preview.logits[static_cast<size_t>(std::clamp(y, 0, h - 1)) * w +
                          std::clamp(x, 0, w - 1)];
  };
  std::vector<int64_t> near;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const bool inside = at(x, y) > 0;
      bool edge = false;
      for (int dy = -1; dy <= 1 && !edge; ++dy) {
        for (int dx = -1; dx <= 1 && !edge; ++dx) {
          const float v = at(x + dx, y + dy);
          edge = std::abs(v) < margin || (v > 0) != inside;
        }
      }
      if (edge) near.push_back(static_cast<int64_t>(y) * w + x);
    }
  }
  return near;
}

LowResMask ComposeMaskBlocks(const LowResMask& preview,
                             const std::vector<int64_t>& tokens,
                             const std::vector<float>& block_logits) {
  const int64_t count = static_cast<int64_t>(preview.logits.size());
  CheckArgument(
      preview.width > 0 && count == int64_t{preview.width} * preview.height,
      "ComposeMaskBlocks: preview size and logits disagree");
  CheckArgument(block_logits.size() == tokens.size() * 16,
                "ComposeMaskBlocks: 16 block logits per token are required");
  LowResMask m;
  m.width = 4 * preview.width;
  m.height = 4 * preview.height;
  m.logits.resize(static_cast<size_t>(m.width) * m.height);
  for (int y = 0; y < m.height; ++y) {
    for (int x = 0; x < m.width; ++x) {
      m.logits[static_cast<size_t>(y) * m.width + x] =
          preview.logits[static_cast<size_t>(y / 4) * preview.width + x / 4];
    }
  }
  for (size_t k = 0; k < tokens.size(); ++k) {
    CheckArgument(tokens[k] >= 0 && tokens[k] < count,
                  "ComposeMaskBlocks: a token outside the preview's grid");
    const int64_t ty = tokens[k] / preview.width;
    const int64_t tx = tokens[k] % preview.width;
    for (size_t c = 0; c < 16; ++c) {
      const int64_t row = 4 * ty + 2 * ((c >> 3) & 1) + ((c >> 1) & 1);
      const int64_t col = 4 * tx + 2 * ((c >> 2) & 1) + (c & 1);
      m.logits[static_cast<size_t>(row * m.width + col)] =
          block_logits[k * 16 + c];
    }
  }
  return m;
}

const char* PromptableOptions::KernelName(Kernel kernel) {
  switch (kernel) {
    case Kernel::kAuto:
      return "auto";
    case Kernel::kOn:
      return "on";
    case Kernel::kBf16:
      return "bf16";
    case Kernel::kOff:
      return "off";
  }
  return "?";
}

PromptableOptions::Kernel PromptableOptions::ParseKernel(
    const std::string& name) {
  return ParseEnumName(
      name, {Kernel::kAuto, Kernel::kOn, Kernel::kBf16, Kernel::kOff},
      KernelName, "decoder kernel");
}

void PromptableOptions::Check() const {
  CheckArgument(!encoder.empty() && !decoder.empty(),
                "mask model: encoder and decoder names are required");
  CheckArgument(decoder_threads >= 0,
                "mask model: decoder_threads must be >= 0");
  CheckArgument(mask_margin_logits >= 0.0f,
                "mask model: mask_margin_logits must be >= 0");
  runtime.Check();
}

std::array<double, 2> ImageToLowRes(const infer::InputTransform& transform,
                                    const LowResMask& low_res, double x,
                                    double y) {
  return {
      (x + 0.5) * transform.scale_x * low_res.width / transform.input_width -
          0.5,
      (y + 0.5) * transform.scale_y * low_res.height / transform.input_height -
          0.5};
}

namespace {

// SAM's bilinear upsampling of low-res logits over the image pixels [x0, x1)
// x [y0, y1): f(x, y, value) per pixel. Each column's and row's taps
// (ImageToLowRes, clamped) once: the same values as per pixel, without the
// per-pixel mapping (most of a stability score's time).
template <class F>
void ForEachUpsampled(const infer::InputTransform& transform,
                      const LowResMask& low_res, int x0, int x1, int y0, int y1,
                      F f) {
  struct Tap {
    int lo = 0, hi = 0;
    float frac = 0;
  };
  const auto tap = [](double s, int cells) {
    s = std::clamp(s, 0.0, static_cast<double>(cells - 1));
    const int i = static_cast<int>(std::floor(s));
    return Tap{i, std::min(i + 1, cells - 1), static_cast<float>(s - i)};
  };
  std::vector<Tap> columns(static_cast<size_t>(std::max(0, x1 - x0)));
  for (int x = x0; x < x1; ++x) {
    columns[x - x0] =
        tap(ImageToLowRes(transform, low_res, x, 0)[0], low_res.width);
  }
  const float* logits = low_res.logits.data();
  for (int y = y0; y < y1; ++y) {
    const Tap row =
        tap(ImageToLowRes(transform, low_res, 0, y)[1], low_res.height);
    const float b = row.frac;
    const float* r0 = logits + static_cast<size_t>(row.lo) * low_res.width;
    const float* r1 = logits + static_cast<size_t>(row.hi) * low_res.width;
    for (int x = x0; x < x1; ++x) {
      const Tap& c = columns[x - x0];
      const float a = c.frac;
      f(x, y,
        (1 - a) * (1 - b) * r0[c.lo] + a * (1 - b) * r0[c.hi] +
            (1 - a) * b * r1[c.lo] + a * b * r1[c.hi]);
    }
  }
}

}  // namespace

Mask PromptableSegmenter::Upsample(const LowResMask& low_res,
                                   float threshold) const {
  const int w = transform_.image_width, h = transform_.image_height;
  Mask mask;
  mask.image_width = w;
  mask.image_height = h;
  mask.predicted_iou = low_res.predicted_iou;
  // Bounding box of the positive low-res cells, grown by one cell: outside it
  // every bilinear sample is <= threshold, so only the box is upsampled.
  int u0 = low_res.width, v0 = low_res.height, u1 = -1, v1 = -1;
  for (int v = 0; v < low_res.height; ++v) {
    for (int u = 0; u < low_res.width; ++u) {
      if (low_res.logits[static_cast<size_t>(v) * low_res.width + u] >
          threshold) {
        u0 = std::min(u0, u);
        v0 = std::min(v0, v);
        u1 = std::max(u1, u);
        v1 = std::max(v1, v);
      }
    }
  }
  if (u1 < 0) return mask;
  const double cell_x = static_cast<double>(transform_.input_width) /
                        low_res.width /
                        transform_.scale_x;  // image pixels per cell
  const double cell_y = static_cast<double>(transform_.input_height) /
                        low_res.height / transform_.scale_y;
  const Box box{
      std::clamp(static_cast<int>(std::floor((u0 - 0.5) * cell_x)), 0, w),
      std::clamp(static_cast<int>(std::floor((v0 - 0.5) * cell_y)), 0, h),
      std::clamp(static_cast<int>(std::ceil((u1 + 1.5) * cell_x)), 0, w),
      std::clamp(static_cast<int>(std::ceil((v1 + 1.5) * cell_y)), 0, h)};
  mask.box = box;
  mask.bits.assign(static_cast<size_t>(box.width()) * box.height(), 0);
  ForEachUpsampled(transform_, low_res, box.x0, box.x1, box.y0, box.y1,
                   [&](int x, int y, float value) {
                     mask.bits[static_cast<size_t>(y - box.y0) * box.width() +
                               (x - box.x0)] = value > threshold;
                   });
  Tighten(&mask);
  return mask;
}

Image<float> PromptableSegmenter::UpsampleLogits(
    const LowResMask& low_res) const {
  const int w = transform_.image_width, h = transform_.image_height;
  Image<float> out(w, h);
  ForEachUpsampled(transform_, low_res, 0, w, 0, h,
                   [&](int x, int y, float value) { out(x, y) = value; });
  return out;
}

float PromptableSegmenter::StabilityScore(const LowResMask& low_res,
                                          float threshold, float offset) const {
  const int w = transform_.image_width, h = transform_.image_height;
  const float low = threshold - offset, high = threshold + offset;
  int u0 = low_res.width, v0 = low_res.height, u1 = -1, v1 = -1;
  for (int v = 0; v < low_res.height; ++v) {
    for (int u = 0; u < low_res.width; ++u) {
      if (low_res.logits[static_cast<size_t>(v) * low_res.width + u] > low) {
        u0 = std::min(u0, u);
        v0 = std::min(v0, v);
        u1 = std::max(u1, u);
        v1 = std::max(v1, v);
      }
    }
  }
  if (u1 < 0) return 1.0f;
  const double cell_x = static_cast<double>(transform_.input_width) /
                        low_res.width / transform_.scale_x;
  const double cell_y = static_cast<double>(transform_.input_height) /
                        low_res.height / transform_.scale_y;
  const int x0 =
      std::clamp(static_cast<int>(std::floor((u0 - 0.5) * cell_x)), 0, w);
  const int y0 =
      std::clamp(static_cast<int>(std::floor((v0 - 0.5) * cell_y)), 0, h);
  const int x1 =
      std::clamp(static_cast<int>(std::ceil((u1 + 1.5) * cell_x)), 0, w);
  const int y1 =
      std::clamp(static_cast<int>(std::ceil((v1 + 1.5) * cell_y)), 0, h);
  int64_t inter = 0, uni = 0;
  ForEachUpsampled(transform_, low_res, x0, x1, y0, y1,
                   [&](int, int, float value) {
                     inter += value > high;
                     uni += value > low;
                   });
  return uni > 0 ? static_cast<float>(inter) / static_cast<float>(uni) : 1.0f;
}

namespace {

// Weighted mean of the embedding's cells ([1, C, h, w]): counts[cell] / total.
std::vector<float> CellMean(const infer::Tensor& embedding,
                            const std::vector<int64_t>& counts, int64_t total) {
  const int c = static_cast<int>(embedding.shape[1]);
  const size_t cells = counts.size();
  std::vector<float> mean(c, 0.0f);
  if (total == 0) return mean;
  for (size_t cell = 0; cell < cells; ++cell) {
    if (counts[cell] == 0) continue;
    const float weight =
        static_cast<float>(counts[cell]) / static_cast<float>(total);
    for (int k = 0; k < c; ++k) {
      mean[k] += weight * embedding.data[static_cast<size_t>(k) * cells + cell];
    }
  }
  return mean;
}

}  // namespace

std::vector<float> PromptableSegmenter::PooledEmbedding(
    const Mask& mask) const {
  CheckArgument(embedding_.shape.size() == 4,
                "PooledEmbedding: no image has been encoded");
  const int h = static_cast<int>(embedding_.shape[2]),
            w = static_cast<int>(embedding_.shape[3]);
  // Count mask pixels per embedding cell, then a weighted mean of the cells.
  std::vector<int64_t> counts(static_cast<size_t>(w) * h, 0);
  const double sx = transform_.scale_x * w / transform_.input_width;
  const double sy = transform_.scale_y * h / transform_.input_height;
  for (int y = mask.box.y0; y < mask.box.y1; ++y) {
    for (int x = mask.box.x0; x < mask.box.x1; ++x) {
      if (!mask.Contains(x, y)) continue;
      const int u = std::min(static_cast<int>((x + 0.5) * sx), w - 1);
      const int v = std::min(static_cast<int>((y + 0.5) * sy), h - 1);
      ++counts[static_cast<size_t>(v) * w + u];
    }
  }
  return CellMean(embedding_, counts, mask.area);
}

std::vector<float> PromptableSegmenter::PooledEmbedding(
    const LowResMask& low_res) const {
  CheckArgument(embedding_.shape.size() == 4,
                "PooledEmbedding: no image has been encoded");
  const int h = static_cast<int>(embedding_.shape[2]),
            w = static_cast<int>(embedding_.shape[3]);
  std::vector<int64_t> counts(static_cast<size_t>(w) * h, 0);
  int64_t total = 0;
  for (int v = 0; v < low_res.height; ++v) {
    for (int u = 0; u < low_res.width; ++u) {
      if (low_res.logits[static_cast<size_t>(v) * low_res.width + u] <= 0) {
        continue;
      }
      const int eu = u * w / low_res.width, ev = v * h / low_res.height;
      ++counts[static_cast<size_t>(ev) * w + eu];
      ++total;
    }
  }
  if (total == 0) return {};
  return CellMean(embedding_, counts, total);
}

std::vector<float> PromptableSegmenter::EmbeddingAt(double x, double y) const {
  CheckArgument(embedding_.shape.size() == 4,
                "EmbeddingAt: no image has been encoded");
  const int c = static_cast<int>(embedding_.shape[1]),
            h = static_cast<int>(embedding_.shape[2]),
            w = static_cast<int>(embedding_.shape[3]);
  const int u = std::clamp(
      static_cast<int>(x * transform_.scale_x * w / transform_.input_width), 0,
      w - 1);
  const int v = std::clamp(
      static_cast<int>(y * transform_.scale_y * h / transform_.input_height), 0,
      h - 1);
  std::vector<float> out(c);
  for (int k = 0; k < c; ++k) {
    out[k] = embedding_.data[(static_cast<size_t>(k) * h + v) * w + u];
  }
  return out;
}

bool MaskPreviewMayPass(const LowResMask& preview, float predicted_iou,
                        const MaskFilter& filter,
                        const infer::InputTransform& transform) {
  if (predicted_iou < filter.min_predicted_iou) return false;
  // Preview cell x is low-res cell 4x + 2 of a 4x finer grid over the model
  // frame; count those whose centre lies on the image (the letterbox's
  // padding counts for nothing in the full-resolution score either).
  const auto inside = [](int cell, int preview_size, int resized, int input) {
    return (4.0 * cell + 2.5) / (4.0 * preview_size) * input < resized;
  };
  const float high = filter.stability_offset, low = -filter.stability_offset;
  int64_t above_high = 0, above_low = 0;
  for (int y = 0; y < preview.height; ++y) {
    if (!inside(y, preview.height, transform.resized_height,
                transform.input_height)) {
      break;
    }
    for (int x = 0; x < preview.width; ++x) {
      if (!inside(x, preview.width, transform.resized_width,
                  transform.input_width)) {
        break;
      }
      const float logit =
          preview.logits[static_cast<size_t>(y) * preview.width + x];
      above_high += logit > high;
      above_low += logit > low;
    }
  }
  if (above_low < 16) return true;  // too few cells to tell
  const double estimate = static_cast<double>(above_high) / above_low;
  const double error = 0.03 + 0.5 / std::sqrt(static_cast<double>(above_low));
  return estimate >= filter.min_stability - error;
}

}  // namespace semrec::segment
