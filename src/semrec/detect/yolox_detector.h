// YOLOX object detection on ONNX: the people tracker's person detector and the
// segmenter's second source of class evidence (any COCO class can be kept).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "semrec/core/image.h"
#include "semrec/detect/box.h"
#include "semrec/infer/image_input.h"
#include "semrec/infer/model_registry.h"
#include "semrec/infer/onnx_model.h"

namespace semrec::detect {

struct YoloxOptions {
  /// Registry name (role detector). The input size and pre-processing come
  /// from the registry entry (yolox_nano: 416x416 letterbox, BGR 0..255,
  /// pad 114).
  std::string model = "yolox_nano";
  infer::OnnxModelOptions runtime;
  /// Keep detections with objectness x class score >= this.
  float score_threshold = 0.3f;
  /// Per-class greedy NMS at this box IoU (YOLOX's demo: 0.45).
  float nms_iou = 0.45f;
  /// Label ids to keep (label set of the entry, COCO-80: 1 = person); empty =
  /// all classes.
  std::vector<int> classes = {1};
  void Check() const;
};

/// One detected object: its box in image pixels, objectness x class score,
/// and label id.
struct LabeledDetection {
  Box box;
  double score = 1.0;
  int class_id = 0;
};

class YoloxDetector {
 public:
  YoloxDetector(const infer::ModelRegistry& registry,
                const YoloxOptions& options);
  /// Detections in image pixels, highest score first.
  std::vector<LabeledDetection> Detect(const ColorImage& rgb) const;

 private:
  YoloxOptions options_;
  std::unique_ptr<infer::OnnxModel> model_;
};

/// Decodes a raw YOLOX output [1, A, 5 + K] (grid-relative, strides 8/16/32
/// over the input frame, scores already sigmoid-activated): cx = (p0 + gx) *
/// s, w = exp(p2) * s, score = objectness x class score; maps boxes back
/// through the letterbox; filters by score and class (id = index +
/// label_offset); per-class NMS. Throws InvalidArgument when A does not match
/// the input size's grids.
std::vector<LabeledDetection> DecodeYolox(
    const infer::Tensor& output, const infer::InputTransform& transform,
    const YoloxOptions& options, int label_offset);

}  // namespace semrec::detect
