// The semantic branch: any "per-pixel logits" model described by the model
// registry (DeepLab, SegFormer, OneFormer semantic exports...) -> one class
// per pixel plus a confidence.
#pragma once

#include <memory>
#include <string>

#include "semrec/core/image.h"
#include "semrec/core/label_map.h"
#include "semrec/infer/image_input.h"
#include "semrec/infer/model_registry.h"
#include "semrec/infer/onnx_model.h"

namespace semrec::segment {

struct SemanticSegmenterOptions {
  /// Registry name of the model (role "semantic").
  std::string model = "mosaic_r4_ade20k";
  /// Threads, provider, model cache.
  infer::OnnxModelOptions runtime;
  void Check() const;
};

struct SemanticResult {
  /// Label ids of the model's label set (output channel + label_offset), at
  /// the input image's size.
  LabelMap labels;
  /// Softmax probability of the chosen class, computed on the logits' grid
  /// and interpolated (a full-resolution softmax over 150 classes would
  /// cost more than the argmax), in [0, 1].
  Image<float> confidence;
};

class SemanticSegmenter {
 public:
  /// Loads the model and its label set. Throws as OnnxModel does, and
  /// InvalidArgument when the entry is not a semantic model.
  SemanticSegmenter(const infer::ModelRegistry& registry,
                    const SemanticSegmenterOptions& options);
  /// Same with an explicit model file (e.g. a user's export), still checked
  /// against the entry's signature.
  SemanticSegmenter(const infer::ModelEntry& entry,
                    const std::filesystem::path& file,
                    const SemanticSegmenterOptions& options);

  /// Runs the model on an RGB image and upsamples the logits bilinearly to
  /// the image size (only the part of the model frame the image covers), then
  /// takes the argmax per pixel.
  SemanticResult Segment(const ColorImage& rgb) const;

  const LabelSet& label_set() const { return label_set_; }
  const infer::ModelEntry& entry() const { return model_->entry(); }

 private:
  void Init();
  std::unique_ptr<infer::OnnxModel> model_;
  LabelSet label_set_;
};

/// Logits [1, K, h, w] (NCHW) or [1, h, w, K] (NHWC) covering the model's
/// input frame -> argmax label (channel + label_offset) and softmax
/// confidence per image pixel; `grid` says where the logit cells sit in the
/// input frame. Exposed for tests.
SemanticResult LogitsToLabels(
    const infer::Tensor& logits, infer::TensorLayout layout,
    const infer::InputTransform& transform, int label_offset,
    infer::GridAlignment grid = infer::GridAlignment::kHalfPixel);

}  // namespace semrec::segment
