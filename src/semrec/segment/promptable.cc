#include "semrec/segment/promptable.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

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

void PromptableOptions::Check() const {
  CheckArgument(
      backend == "sam" || backend == "sam2",
      "mask model: backend must be sam or sam2, not '" + backend + "'");
  CheckArgument(!encoder.empty() && !decoder.empty(),
                "mask model: encoder and decoder names are required");
  CheckArgument(decoder_threads >= 0,
                "mask model: decoder_threads must be >= 0");
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
  const auto at = [&](int u, int v) {
    u = std::clamp(u, 0, low_res.width - 1);
    v = std::clamp(v, 0, low_res.height - 1);
    return low_res.logits[static_cast<size_t>(v) * low_res.width + u];
  };
  for (int y = box.y0; y < box.y1; ++y) {
    for (int x = box.x0; x < box.x1; ++x) {
      auto [s, t] = ImageToLowRes(transform_, low_res, x, y);
      s = std::clamp(s, 0.0, static_cast<double>(low_res.width - 1));
      t = std::clamp(t, 0.0, static_cast<double>(low_res.height - 1));
      const int i = static_cast<int>(std::floor(s)),
                j = static_cast<int>(std::floor(t));
      const float a = static_cast<float>(s - i), b = static_cast<float>(t - j);
      const float value = (1 - a) * (1 - b) * at(i, j) +
                          a * (1 - b) * at(i + 1, j) +
                          (1 - a) * b * at(i, j + 1) + a * b * at(i + 1, j + 1);
      mask.bits[static_cast<size_t>(y - box.y0) * box.width() + (x - box.x0)] =
          value > threshold;
    }
  }
  Tighten(&mask);
  return mask;
}

Image<float> PromptableSegmenter::UpsampleLogits(
    const LowResMask& low_res) const {
  const int w = transform_.image_width, h = transform_.image_height;
  Image<float> out(w, h);
  const auto at = [&](int u, int v) {
    u = std::clamp(u, 0, low_res.width - 1);
    v = std::clamp(v, 0, low_res.height - 1);
    return low_res.logits[static_cast<size_t>(v) * low_res.width + u];
  };
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      auto [s, t] = ImageToLowRes(transform_, low_res, x, y);
      s = std::clamp(s, 0.0, static_cast<double>(low_res.width - 1));
      t = std::clamp(t, 0.0, static_cast<double>(low_res.height - 1));
      const int i = static_cast<int>(std::floor(s)),
                j = static_cast<int>(std::floor(t));
      const float a = static_cast<float>(s - i), b = static_cast<float>(t - j);
      out(x, y) = (1 - a) * (1 - b) * at(i, j) + a * (1 - b) * at(i + 1, j) +
                  (1 - a) * b * at(i, j + 1) + a * b * at(i + 1, j + 1);
    }
  }
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
  const auto at = [&](int u, int v) {
    u = std::clamp(u, 0, low_res.width - 1);
    v = std::clamp(v, 0, low_res.height - 1);
    return low_res.logits[static_cast<size_t>(v) * low_res.width + u];
  };
  int64_t inter = 0, uni = 0;
  for (int y = y0; y < y1; ++y) {
    for (int x = x0; x < x1; ++x) {
      auto [s, t] = ImageToLowRes(transform_, low_res, x, y);
      s = std::clamp(s, 0.0, static_cast<double>(low_res.width - 1));
      t = std::clamp(t, 0.0, static_cast<double>(low_res.height - 1));
      const int i = static_cast<int>(std::floor(s)),
                j = static_cast<int>(std::floor(t));
      const float a = static_cast<float>(s - i), b = static_cast<float>(t - j);
      const float value = (1 - a) * (1 - b) * at(i, j) +
                          a * (1 - b) * at(i + 1, j) +
                          (1 - a) * b * at(i, j + 1) + a * b * at(i + 1, j + 1);
      inter += value > high;
      uni += value > low;
    }
  }
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

namespace {

// SAM's ONNX prompt encoding: points then box corners (labels 2, 3); without
// a box a padding point (label -1) is appended, as the exporter expects.
void EncodePrompt(const Prompt& prompt, const infer::InputTransform& t,
                  infer::Tensor* coords, infer::Tensor* labels) {
  CheckArgument(prompt.points.size() == prompt.labels.size(),
                "prompt: one label per point is required");
  CheckArgument(!prompt.points.empty() || prompt.box,
                "prompt: needs at least one point or a box");
  std::vector<float> xy, l;
  for (size_t i = 0; i < prompt.points.size(); ++i) {
    xy.push_back(static_cast<float>(prompt.points[i][0] * t.scale_x));
    xy.push_back(static_cast<float>(prompt.points[i][1] * t.scale_y));
    l.push_back(static_cast<float>(prompt.labels[i]));
  }
  if (prompt.box) {
    const Box& b = *prompt.box;
    xy.insert(xy.end(), {static_cast<float>(b.x0 * t.scale_x),
                         static_cast<float>(b.y0 * t.scale_y),
                         static_cast<float>(b.x1 * t.scale_x),
                         static_cast<float>(b.y1 * t.scale_y)});
    l.insert(l.end(), {2.0f, 3.0f});
  } else {
    xy.insert(xy.end(), {0.0f, 0.0f});
    l.push_back(-1.0f);
  }
  const int64_t n = static_cast<int64_t>(l.size());
  *coords = infer::Tensor{{1, n, 2}, std::move(xy)};
  *labels = infer::Tensor{{1, n}, std::move(l)};
}

const infer::Tensor& Output(const std::map<std::string, infer::Tensor>& out,
                            const std::string& name, const std::string& model) {
  auto it = out.find(name);
  if (it == out.end()) {
    throw Error(
        fmt::format("mask decoder '{}' has no output '{}'", model, name));
  }
  return it->second;
}

// Picks the candidate with the highest predicted IoU from [1, M, h, w] masks.
LowResMask BestOf(const infer::Tensor& masks, const infer::Tensor& ious,
                  const std::string& model) {
  if (masks.shape.size() != 4 || masks.shape[0] != 1 || masks.shape[1] < 1 ||
      ious.data.size() != static_cast<size_t>(masks.shape[1])) {
    throw Error(
        fmt::format("mask decoder '{}': unexpected mask/IoU shapes", model));
  }
  const int m = static_cast<int>(masks.shape[1]);
  const int best = static_cast<int>(
      std::max_element(ious.data.begin(), ious.data.end()) - ious.data.begin());
  LowResMask out;
  out.height = static_cast<int>(masks.shape[2]);
  out.width = static_cast<int>(masks.shape[3]);
  const size_t plane = static_cast<size_t>(out.width) * out.height;
  out.logits.assign(masks.data.begin() + best * plane,
                    masks.data.begin() + (best + 1) * plane);
  out.predicted_iou = ious.data[best];
  (void)m;
  return out;
}

bool HasOutput(const infer::OnnxModel& model, const std::string& name) {
  const auto& outs = model.session().outputs();
  return std::any_of(outs.begin(), outs.end(), [&](const infer::TensorInfo& o) {
    return o.name == name;
  });
}

bool SplitInstalled(const infer::ModelRegistry& registry,
                    const infer::ModelEntry& decoder,
                    const infer::OnnxModelOptions& runtime) {
  return std::filesystem::exists(
             infer::ModelFile(registry.Get(decoder.split_image), runtime)) &&
         std::filesystem::exists(
             infer::ModelFile(registry.Get(decoder.split_prompt), runtime));
}

class SamSegmenter : public PromptableSegmenter {
 public:
  SamSegmenter(const infer::ModelRegistry& registry,
               const PromptableOptions& options) {
    encoder_ = std::make_unique<infer::OnnxModel>(registry.Get(options.encoder),
                                                  options.runtime);
    infer::OnnxModelOptions dec = options.runtime;
    dec.intra_op_threads = options.decoder_threads;
    const infer::ModelEntry& entry = registry.Get(options.decoder);
    bool split = options.split_decoder && !entry.split_image.empty();
    if (split && !SplitInstalled(registry, entry, options.runtime)) {
      spdlog::warn(
          "mask decoder '{}': its split parts are not installed (run "
          "scripts/setup); decoding with the whole export, about half as fast",
          entry.name);
      split = false;
    }
    if (split) {
      image_part_ = std::make_unique<infer::OnnxModel>(
          registry.Get(entry.split_image), options.runtime);
      decoder_ = std::make_unique<infer::OnnxModel>(
          registry.Get(entry.split_prompt), dec);
      // A prompt part with a preview leaves the upscaling to the mask part.
      if (HasOutput(*decoder_, "mask_preview")) {
        if (!entry.split_masks.empty() &&
            std::filesystem::exists(infer::ModelFile(
                registry.Get(entry.split_masks), options.runtime))) {
          mask_part_ = std::make_unique<infer::OnnxModel>(
              registry.Get(entry.split_masks), dec);
        } else {
          spdlog::warn(
              "mask decoder '{}': its prompt part needs the mask part, which "
              "is not installed (run scripts/setup); decoding with the whole "
              "export, about half as fast",
              entry.name);
          image_part_.reset();
          decoder_ = std::make_unique<infer::OnnxModel>(entry, dec);
        }
      }
    } else {
      decoder_ = std::make_unique<infer::OnnxModel>(entry, dec);
    }
    CheckArgument(encoder_->entry().input.has_value(),
                  "mask encoder '" + options.encoder + "' has no input spec");
  }

  void SetImage(const ColorImage& rgb) override {
    const auto& spec = *encoder_->entry().input;
    auto out = encoder_->Run(
        {{spec.name, infer::ImageToTensor(rgb, spec, &transform_)}});
    const std::string name =
        encoder_->entry().output ? encoder_->entry().output->name : "output";
    embedding_ = Output(out, name, encoder_->entry().name);
    image_features_.clear();
    if (image_part_) {
      image_features_ = image_part_->RunRefs(ImageSide(*image_part_));
    }
  }

  LowResMask Decode(const Prompt& prompt) const override {
    return Run(prompt, nullptr);
  }

  LowResMask DecodeUnlessRejected(const Prompt& prompt,
                                  const MaskFilter& filter) const override {
    return Run(prompt, &filter);
  }

 private:
  LowResMask Run(const Prompt& prompt, const MaskFilter* filter) const {
    CheckArgument(!embedding_.shape.empty(), "SAM: SetImage() was not called");
    infer::Tensor coords, labels;
    EncodePrompt(prompt, transform_, &coords, &labels);
    infer::TensorRefs in = ImageSide(*decoder_);
    in["point_coords"] = &coords;
    in["point_labels"] = &labels;
    const auto out = decoder_->RunRefs(in);
    const std::string& name = decoder_->entry().name;
    const infer::Tensor& iou = Output(out, "iou_predictions", name);
    if (!mask_part_) {
      return BestOf(Output(out, "low_res_masks", name), iou, name);
    }
    // The prompt part has chosen the mask; judge its preview before paying
    // for the upscaling.
    if (filter != nullptr) {
      const infer::Tensor& p = Output(out, "mask_preview", name);
      LowResMask preview;
      if (p.shape.size() != 4 || iou.data.size() != 1) {
        throw Error(fmt::format(
            "mask decoder '{}': unexpected preview/IoU shapes", name));
      }
      preview.height = static_cast<int>(p.shape[2]);
      preview.width = static_cast<int>(p.shape[3]);
      preview.logits = p.data;
      if (!MaskPreviewMayPass(preview, iou.data[0], *filter, transform_)) {
        LowResMask rejected;
        rejected.predicted_iou = iou.data[0];
        rejected.rejected_early = true;
        return rejected;
      }
    }
    infer::TensorRefs mask_in;
    for (const infer::TensorInfo& info : mask_part_->session().inputs()) {
      mask_in[info.name] = &Output(out, info.name, name);
    }
    const std::string& mask_name = mask_part_->entry().name;
    const auto masks = mask_part_->RunRefs(mask_in);
    return BestOf(Output(masks, "low_res_masks", mask_name), iou, mask_name);
  }

  // The inputs of `model` that do not depend on the prompt, by reference:
  // the embedding, the image part's outputs, and constants (no mask input;
  // orig_im_size = the low-res size, so the export's upsampling to it costs
  // nothing: only kept masks are upsampled, by us).
  infer::TensorRefs ImageSide(const infer::OnnxModel& model) const {
    infer::TensorRefs in;
    for (const infer::TensorInfo& info : model.session().inputs()) {
      const std::string& n = info.name;
      if (n == "point_coords" || n == "point_labels") continue;
      if (auto it = image_features_.find(n); it != image_features_.end()) {
        in[n] = &it->second;
      } else if (n == "image_embeddings") {
        in[n] = &embedding_;
      } else if (n == "mask_input") {
        in[n] = &no_mask_;
      } else if (n == "has_mask_input") {
        in[n] = &has_no_mask_;
      } else if (n == "orig_im_size") {
        in[n] = &low_res_size_;
      } else {
        throw Error(fmt::format(
            "mask decoder '{}': input '{}' is neither a SAM decoder input nor "
            "an output of the image part; re-run scripts/setup",
            model.entry().name, n));
      }
    }
    return in;
  }

  std::unique_ptr<infer::OnnxModel> encoder_, image_part_, decoder_, mask_part_;
  std::map<std::string, infer::Tensor> image_features_;
  const infer::Tensor no_mask_ = infer::Tensor::Zeros({1, 1, 256, 256});
  const infer::Tensor has_no_mask_ = infer::Tensor::Zeros({1});
  const infer::Tensor low_res_size_{{2}, {64.0f, 64.0f}};
};

class Sam2Segmenter : public PromptableSegmenter {
 public:
  Sam2Segmenter(const infer::ModelRegistry& registry,
                const PromptableOptions& options) {
    encoder_ = std::make_unique<infer::OnnxModel>(registry.Get(options.encoder),
                                                  options.runtime);
    infer::OnnxModelOptions dec = options.runtime;
    dec.intra_op_threads = options.decoder_threads;
    decoder_ =
        std::make_unique<infer::OnnxModel>(registry.Get(options.decoder), dec);
    CheckArgument(encoder_->entry().input.has_value(),
                  "mask encoder '" + options.encoder + "' has no input spec");
    for (const auto& info : decoder_->session().inputs()) {
      if (info.name == "orig_im_size") wants_size_ = true;
    }
  }

  void SetImage(const ColorImage& rgb) override {
    const auto& spec = *encoder_->entry().input;
    features_ = encoder_->Run(
        {{spec.name, infer::ImageToTensor(rgb, spec, &transform_)}});
    embedding_ = Output(features_, "image_embed", encoder_->entry().name);
  }

  LowResMask Decode(const Prompt& prompt) const override {
    CheckArgument(!features_.empty(), "SAM2: SetImage() was not called");
    infer::Tensor coords, labels;
    EncodePrompt(prompt, transform_, &coords, &labels);
    const std::string& enc = encoder_->entry().name;
    std::map<std::string, infer::Tensor> in;
    in["image_embed"] = Output(features_, "image_embed", enc);
    in["high_res_feats_0"] = Output(features_, "high_res_feats_0", enc);
    in["high_res_feats_1"] = Output(features_, "high_res_feats_1", enc);
    in["point_coords"] = std::move(coords);
    in["point_labels"] = std::move(labels);
    in["mask_input"] = infer::Tensor::Zeros({1, 1, 256, 256});
    in["has_mask_input"] = infer::Tensor::Zeros({1});
    if (wants_size_) in["orig_im_size"] = infer::Tensor{{2}, {64.0f, 64.0f}};
    const auto out = decoder_->Run(in);
    const std::string& name = decoder_->entry().name;
    LowResMask best = BestOf(Output(out, "masks", name),
                             Output(out, "iou_predictions", name), name);
    if (auto it = out.find("obj_ptr"); it != out.end()) {
      best.object_pointer = it->second.data;
    }
    return best;
  }

 private:
  std::unique_ptr<infer::OnnxModel> encoder_, decoder_;
  std::map<std::string, infer::Tensor> features_;
  bool wants_size_ = false;
};

}  // namespace

std::unique_ptr<PromptableSegmenter> PromptableSegmenter::Create(
    const infer::ModelRegistry& registry, const PromptableOptions& options) {
  options.Check();
  if (options.backend == "sam") {
    return std::make_unique<SamSegmenter>(registry, options);
  }
  return std::make_unique<Sam2Segmenter>(registry, options);
}

}  // namespace semrec::segment
