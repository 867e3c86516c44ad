// The SAM and SAM2 backends of PromptableSegmenter: ONNX encoder + decoder,
// SAM's decoder optionally as the parts scripts/split_sam_decoder.py makes
// (image part once per image, prompt part per prompt, mask part only for
// masks whose preview can pass the caller's filters).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "semrec/core/error.h"
#include "semrec/sam/kernel.h"
#include "semrec/sam/kernel_ops.h"
#include "semrec/segment/promptable.h"

namespace semrec::segment {

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
    mask_margin_logits_ = options.mask_margin_logits;
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
          mask_part_blocks_ = HasOutput(*mask_part_, "block_logits");
          LoadKernel(registry, entry, options);
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
    if (kernel_) {
      kernel_image_ = kernel_->Prepare(embedding_.data, embedding_.shape);
    } else if (image_part_) {
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

  std::vector<LowResMask> DecodeBatchUnlessRejected(
      const std::vector<Prompt>& prompts,
      const MaskFilter& filter) const override {
    if (!kernel_) {
      return PromptableSegmenter::DecodeBatchUnlessRejected(prompts, filter);
    }
    CheckArgument(!embedding_.shape.empty(), "SAM: SetImage() was not called");
    return RunKernel(prompts, &filter);
  }

 private:
  // The split's image and prompt parts as semrec's kernel, when asked for
  // and installed (it needs the mask part's any-token form).
  void LoadKernel(const infer::ModelRegistry& registry,
                  const infer::ModelEntry& entry,
                  const PromptableOptions& options) {
    using Kernel = PromptableOptions::Kernel;
    // Asked for by name, bf16 products must be there (not a silent fallback).
    if (options.decoder_kernel == Kernel::kBf16 &&
        !sam::kernel_ops::HasBf16()) {
      throw InvalidArgument(
          "decoder kernel 'bf16' needs a CPU with AVX512_BF16 (this one has "
          "not; use 'on' for fp32 products)");
    }
    if (options.decoder_kernel == Kernel::kOff || !mask_part_blocks_ ||
        entry.split_kernel.empty() ||
        (options.decoder_kernel == Kernel::kAuto &&
         std::string(sam::kernel_ops::SimdLevel()) != "avx512")) {
      return;
    }
    const std::filesystem::path file =
        infer::ModelFile(registry.Get(entry.split_kernel), options.runtime);
    if (!std::filesystem::exists(file)) {
      spdlog::warn(
          "mask decoder '{}': its kernel weights {} are not installed (run "
          "scripts/setup); decoding with ONNX Runtime, slower",
          entry.name, file.string());
      return;
    }
    const bool bf16 =
        options.decoder_kernel == Kernel::kBf16 ||
        (options.decoder_kernel == Kernel::kAuto && sam::kernel_ops::HasBf16());
    kernel_ = std::make_unique<sam::SamKernel>(
        file, bf16 ? sam::SamKernel::Precision::kBf16
                   : sam::SamKernel::Precision::kFp32);
    kernel_upscales_ = options.kernel_upscales && kernel_->CanUpscale();
    if (options.kernel_upscales && !kernel_->CanUpscale()) {
      spdlog::warn(
          "mask decoder '{}': its kernel weights {} predate the kernel's mask "
          "part (run scripts/setup); upscaling with ONNX Runtime, slower",
          entry.name, file.string());
    }
  }

  // A prompt as the kernel takes it: points in the model frame, labels.
  void KernelPoints(const Prompt& prompt,
                    std::vector<std::array<float, 2>>* points,
                    std::vector<float>* labels) const {
    infer::Tensor coords, label_tensor;
    EncodePrompt(prompt, transform_, &coords, &label_tensor);
    points->resize(label_tensor.data.size());
    for (size_t i = 0; i < points->size(); ++i) {
      (*points)[i] = {coords.data[2 * i], coords.data[2 * i + 1]};
    }
    *labels = std::move(label_tensor.data);
  }

  // The kernel's outputs under the prompt part's names, filtered and
  // upscaled.
  LowResMask KernelResult(const sam::SamKernel::Output& result,
                          const MaskFilter* filter) const {
    std::map<std::string, infer::Tensor> out;
    out["mask_hyper"] =
        infer::Tensor{{1, 1, static_cast<int64_t>(result.mask_hyper.size())},
                      result.mask_hyper};
    LowResMask preview;
    preview.height = static_cast<int>(embedding_.shape[2]);
    preview.width = static_cast<int>(embedding_.shape[3]);
    preview.logits = result.preview;
    return FilterAndUpscale(out, preview, result.predicted_iou, filter,
                            &result);
  }

  // Run() through the kernel, for any number of prompts (decoded together).
  std::vector<LowResMask> RunKernel(const std::vector<Prompt>& prompts,
                                    const MaskFilter* filter) const {
    const size_t n = prompts.size();
    std::vector<std::vector<std::array<float, 2>>> points(n);
    std::vector<std::vector<float>> labels(n);
    // Per thread, so their 4 MB of image tokens are not allocated anew.
    thread_local std::vector<sam::SamKernel::Output> results;
    if (results.size() < n) results.resize(n);
    std::vector<sam::SamKernel::Request> requests(n);
    for (size_t i = 0; i < n; ++i) {
      KernelPoints(prompts[i], &points[i], &labels[i]);
      requests[i] = {&points[i], &labels[i], &results[i]};
    }
    kernel_->DecodeBatch(kernel_image_, requests);
    std::vector<LowResMask> out(n);
    for (size_t i = 0; i < n; ++i) out[i] = KernelResult(results[i], filter);
    return out;
  }

  LowResMask Run(const Prompt& prompt, const MaskFilter* filter) const {
    CheckArgument(!embedding_.shape.empty(), "SAM: SetImage() was not called");
    if (kernel_) return RunKernel({prompt}, filter).front();
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
    const infer::Tensor& p = Output(out, "mask_preview", name);
    if (p.shape.size() != 4 || iou.data.size() != 1) {
      throw Error(fmt::format(
          "mask decoder '{}': unexpected preview/IoU shapes", name));
    }
    LowResMask preview;
    preview.height = static_cast<int>(p.shape[2]);
    preview.width = static_cast<int>(p.shape[3]);
    preview.logits = p.data;
    return FilterAndUpscale(out, preview, iou.data[0], filter);
  }

  // Rejected early when the preview cannot pass `filter`, else upscaled.
  // `decoded`: the kernel's result (it computes the upscaling tokens the
  // mask part needs), or null (`out` holds them all).
  LowResMask FilterAndUpscale(
      const std::map<std::string, infer::Tensor>& out,
      const LowResMask& preview, float predicted_iou, const MaskFilter* filter,
      const sam::SamKernel::Output* decoded = nullptr) const {
    if (filter != nullptr &&
        !MaskPreviewMayPass(preview, predicted_iou, *filter, transform_)) {
      LowResMask rejected = preview;
      rejected.predicted_iou = predicted_iou;
      rejected.rejected_early = true;
      return rejected;
    }
    LowResMask mask = Upscale(out, preview, filter != nullptr, decoded);
    mask.predicted_iou = predicted_iou;
    return mask;
  }

  // The mask part's low-res mask from the prompt part's outputs `out`:
  // every token, or (`filtered`, with a margin) those near the mask's edge.
  LowResMask Upscale(const std::map<std::string, infer::Tensor>& out,
                     const LowResMask& preview, bool filtered,
                     const sam::SamKernel::Output* decoded) const {
    const std::string& name = decoder_->entry().name;
    infer::TensorRefs mask_in;
    for (const infer::TensorInfo& info : mask_part_->session().inputs()) {
      if (decoded != nullptr && info.name == "upscaling_tokens") continue;
      mask_in[info.name] = &Output(out, info.name, name);
    }
    const std::string& mask_name = mask_part_->entry().name;
    if (!mask_part_blocks_) {  // a split made before block_logits
      const auto masks = mask_part_->RunRefs(mask_in);
      return BestOf(Output(masks, "low_res_masks", mask_name),
                    Output(out, "iou_predictions", name), mask_name);
    }
    const auto count = static_cast<int64_t>(preview.logits.size());
    std::vector<int64_t> chosen;
    if (filtered && mask_margin_logits_ > 0.0f) {
      chosen = TokensNearMaskEdge(preview, mask_margin_logits_);
    } else {
      chosen.resize(static_cast<size_t>(count));
      for (int64_t t = 0; t < count; ++t) chosen[t] = t;
    }
    infer::Tensor picked;
    if (decoded != nullptr && kernel_upscales_) {
      std::vector<float> blocks(chosen.size() * sam::SamKernel::kCellsPerToken);
      kernel_->UpscaleBlocks(kernel_image_, *decoded, chosen, blocks.data());
      return ComposeMaskBlocks(preview, chosen, blocks);
    }
    if (decoded != nullptr) {  // weights made before the kernel upscaled
      picked.shape = {1, static_cast<int64_t>(chosen.size()), 256};
      picked.data.resize(chosen.size() * 256);
      kernel_->UpscalingTokens(kernel_image_, *decoded, chosen,
                               picked.data.data());
      mask_in["upscaling_tokens"] = &picked;
      return UpscaleTokens(mask_in, preview, chosen);
    }
    const infer::Tensor& tokens = Output(out, "upscaling_tokens", name);
    if (tokens.shape.size() != 3 || tokens.shape[1] != count) {
      throw Error(fmt::format(
          "mask decoder '{}': upscaling_tokens do not match the preview",
          name));
    }
    if (filtered && mask_margin_logits_ > 0.0f) {
      const auto channels = static_cast<size_t>(tokens.shape[2]);
      picked.shape = {1, static_cast<int64_t>(chosen.size()), tokens.shape[2]};
      picked.data.resize(chosen.size() * channels);
      for (size_t k = 0; k < chosen.size(); ++k) {
        std::copy_n(tokens.data.begin() + chosen[k] * channels, channels,
                    picked.data.begin() + k * channels);
      }
      mask_in["upscaling_tokens"] = &picked;
    }
    return UpscaleTokens(mask_in, preview, chosen);
  }

  // The mask part on the upscaling tokens of `chosen` (in `mask_in`), the
  // other tokens' cells from the preview.
  LowResMask UpscaleTokens(const infer::TensorRefs& mask_in,
                           const LowResMask& preview,
                           const std::vector<int64_t>& chosen) const {
    const std::string& mask_name = mask_part_->entry().name;
    std::map<std::string, infer::Tensor> masks;
    if (!chosen.empty()) masks = mask_part_->RunRefs(mask_in);
    const std::vector<float>& blocks =
        chosen.empty() ? kNoBlocks
                       : Output(masks, "block_logits", mask_name).data;
    if (blocks.size() != chosen.size() * 16) {
      throw Error(fmt::format(
          "mask decoder '{}': {} block logits for {} tokens (expected 16 each)",
          mask_name, blocks.size(), chosen.size()));
    }
    return ComposeMaskBlocks(preview, chosen, blocks);
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
  std::unique_ptr<sam::SamKernel> kernel_;  // replaces image_part_ and decoder_
  sam::SamKernel::Image kernel_image_;
  float mask_margin_logits_ = 0.0f;
  // The mask part takes any tokens (block_logits).
  bool mask_part_blocks_ = false;
  bool kernel_upscales_ = false;  // the kernel's own mask part
  static inline const std::vector<float> kNoBlocks{};
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
  if (options.backend == infer::MaskBackend::kSam) {
    return std::make_unique<SamSegmenter>(registry, options);
  }
  return std::make_unique<Sam2Segmenter>(registry, options);
}

}  // namespace semrec::segment
