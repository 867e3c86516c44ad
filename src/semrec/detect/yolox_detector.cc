#include "semrec/detect/yolox_detector.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "semrec/core/error.h"

namespace semrec::detect {

void YoloxOptions::Check() const {
  CheckArgument(!model.empty(), "detector: model name is empty");
  CheckArgument(score_threshold >= 0 && score_threshold <= 1,
                "detector: score_threshold must be in [0, 1]");
  CheckArgument(nms_iou > 0 && nms_iou <= 1,
                "detector: nms_iou must be in (0, 1]");
  runtime.Check();
}

std::vector<LabeledDetection> DecodeYolox(const infer::Tensor& output,
                                          const infer::InputTransform& t,
                                          const YoloxOptions& options,
                                          int label_offset) {
  CheckArgument(
      output.shape.size() == 3 && output.shape[0] == 1 && output.shape[2] > 5,
      fmt::format("detector: output must be [1, anchors, 5 + "
                  "classes], got [{}]",
                  fmt::join(output.shape, ",")));
  const int64_t anchors = output.shape[1], width = output.shape[2];
  const int num_classes = static_cast<int>(width - 5);
  int64_t expected = 0;
  for (int s : {8, 16, 32}) {
    expected += static_cast<int64_t>(t.input_width / s) * (t.input_height / s);
  }
  CheckArgument(anchors == expected,
                fmt::format("detector: {} anchors, but a {}x{} input with "
                            "strides 8/16/32 has {}",
                            anchors, t.input_width, t.input_height, expected));
  std::vector<LabeledDetection> candidates;
  int64_t a = 0;
  for (int s : {8, 16, 32}) {
    const int gw = t.input_width / s, gh = t.input_height / s;
    for (int gy = 0; gy < gh; ++gy) {
      for (int gx = 0; gx < gw; ++gx, ++a) {
        const float* p = &output.data[static_cast<size_t>(a) * width];
        const int best =
            static_cast<int>(std::max_element(p + 5, p + width) - (p + 5));
        const double score = static_cast<double>(p[4]) * p[5 + best];
        if (score < options.score_threshold) continue;
        const int id = best + label_offset;
        if (!options.classes.empty() &&
            std::find(options.classes.begin(), options.classes.end(), id) ==
                options.classes.end()) {
          continue;
        }
        const double cx = (p[0] + gx) * s, cy = (p[1] + gy) * s;
        const double w = std::exp(p[2]) * s, h = std::exp(p[3]) * s;
        LabeledDetection d;
        d.class_id = id;
        d.score = score;
        d.box = {(cx - w / 2) / t.scale_x, (cy - h / 2) / t.scale_y,
                 w / t.scale_x, h / t.scale_y};
        candidates.push_back(d);
      }
    }
  }
  (void)num_classes;
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const LabeledDetection& x, const LabeledDetection& y) {
                     return x.score > y.score;
                   });
  std::vector<LabeledDetection> kept;
  for (const auto& c : candidates) {
    const bool suppressed =
        std::any_of(kept.begin(), kept.end(), [&](const LabeledDetection& k) {
          return k.class_id == c.class_id &&
                 Iou(k.box, c.box) > options.nms_iou;
        });
    if (!suppressed) kept.push_back(c);
  }
  return kept;
}

YoloxDetector::YoloxDetector(const infer::ModelRegistry& registry,
                             const YoloxOptions& options)
    : options_(options) {
  options_.Check();
  const infer::ModelEntry& entry = registry.Get(options_.model);
  CheckArgument(
      entry.role == infer::ModelRole::kDetector && entry.input && entry.output,
      "model '" + entry.name + "' is not a detector (role '" +
          infer::ModelRoleName(entry.role) + "')");
  model_ = std::make_unique<infer::OnnxModel>(entry, options_.runtime);
}

std::vector<LabeledDetection> YoloxDetector::Detect(
    const ColorImage& rgb) const {
  const infer::ModelEntry& e = model_->entry();
  infer::InputTransform transform;
  auto outputs = model_->Run(
      {{e.input->name, infer::ImageToTensor(rgb, *e.input, &transform)}});
  auto it = outputs.find(e.output->name);
  if (it == outputs.end()) {
    throw Error("detector '" + e.name + "' has no output '" + e.output->name +
                "'");
  }
  return DecodeYolox(it->second, transform, options_, e.label_offset);
}

}  // namespace semrec::detect
