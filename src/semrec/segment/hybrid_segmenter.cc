#include "semrec/segment/hybrid_segmenter.h"

#include <string>

#include "semrec/core/error.h"
#include "semrec/core/stopwatch.h"
#include "semrec/io/label_set_io.h"

namespace semrec::segment {

void HybridSegmenterOptions::Check() const {
  semantic.Check();
  if (use_masks) masks.Check();
  objects.Check();
  CheckArgument(!objects.enabled() || use_masks,
                "hybrid segmenter: the object detector needs the mask model "
                "(its boxes are prompts)");
}

HybridSegmenter::HybridSegmenter(const infer::ModelRegistry& registry,
                                 const HybridSegmenterOptions& options)
    : options_(options) {
  options_.Check();
  semantic_ = std::make_unique<SemanticSegmenter>(registry, options_.semantic);
  if (options_.use_masks) {
    masks_ = MaskGenerator::Create(registry, options_.masks);
  }
  if (options_.objects.enabled()) {
    detect::YoloxOptions detector;
    detector.model = options_.objects.model;
    detector.runtime = options_.objects.runtime;
    detector.score_threshold = options_.objects.score_threshold;
    detector.classes.clear();
    detector_ = std::make_unique<detect::YoloxDetector>(registry, detector);
    const std::string& detector_set = registry.Get(detector.model).label_set;
    const std::filesystem::path map_file =
        options_.objects.class_map.empty()
            ? DetectorClassMap::DefaultPath(detector_set,
                                            semantic_->entry().label_set)
            : std::filesystem::path(options_.objects.class_map);
    CheckArgument(std::filesystem::exists(map_file),
                  "object detector: no class map " + map_file.string() +
                      " from " + detector_set + " to " +
                      semantic_->entry().label_set +
                      " (write one: JSON {\"detector class\": \"label "
                      "class\"}, see data/class_maps/)");
    class_map_ = DetectorClassMap::Load(
        map_file, io::LoadLabelSet(detector_set), semantic_->label_set());
  }
}

HybridResult HybridSegmenter::Segment(
    const ColorImage& rgb,
    const std::vector<detect::LabeledDetection>* detections) {
  return Run(rgb, nullptr, std::nullopt, detections);
}

std::vector<detect::LabeledDetection> HybridSegmenter::DetectObjects(
    const ColorImage& rgb) const {
  CheckArgument(detector_ != nullptr,
                "hybrid segmenter: the object detector is off");
  return detector_->Detect(rgb);
}

SemanticResult HybridSegmenter::SegmentSemantic(const ColorImage& rgb) {
  return semantic_->Segment(rgb);
}

HybridResult HybridSegmenter::SegmentWhere(
    const ColorImage& rgb, const Image<uint8_t>& prompt_region,
    std::optional<SemanticResult> semantic,
    const std::vector<detect::LabeledDetection>* detections) {
  CheckArgument(prompt_region.SameSize(rgb.width(), rgb.height()),
                "hybrid segmenter: the prompt region is " +
                    std::to_string(prompt_region.width()) + "x" +
                    std::to_string(prompt_region.height()) + ", the image " +
                    std::to_string(rgb.width()) + "x" +
                    std::to_string(rgb.height()));
  CheckArgument(
      !semantic || semantic->labels.SameSize(rgb.width(), rgb.height()),
      "hybrid segmenter: the semantic labels' size differs from the image's");
  return Run(rgb, &prompt_region, std::move(semantic), detections);
}

void HybridSegmenter::AddObjectEvidence(
    const ColorImage& rgb, const Image<uint8_t>* prompt_region,
    const std::vector<detect::LabeledDetection>* detections,
    HybridResult* result) {
  Stopwatch watch;
  const std::vector<detect::LabeledDetection> raw =
      detections ? std::vector<detect::LabeledDetection>{}
                 : detector_->Detect(rgb);
  result->detect_seconds = watch.Lap();
  std::vector<ObjectDetection> mapped = MapDetections(
      detections ? *detections : raw, class_map_,
      options_.objects.score_threshold, rgb.width(), rgb.height());
  if (prompt_region != nullptr) {
    std::erase_if(mapped, [&](const ObjectDetection& d) {
      return (*prompt_region)((d.box.x0 + d.box.x1) / 2,
                              (d.box.y0 + d.box.y1) / 2) == 0;
    });
  }
  if (mapped.empty()) return;
  masks_->EncodeUnlessCurrent(rgb);
  std::vector<Mask> detection_masks = DecodeDetectionMasks(
      masks_->model(), mapped, options_.masks.min_region_area_px);
  ObjectEvidence evidence =
      AttachDetections(std::move(result->masks), mapped,
                       std::move(detection_masks), options_.objects);
  result->masks = std::move(evidence.masks);
  result->mask_evidence = std::move(evidence.evidence);
  result->mask_detection = std::move(evidence.detection);
  result->mask_part_of = std::move(evidence.part_of);
  result->detections_matched = evidence.matched;
  result->detections_added = evidence.added;
  result->detection_parts = evidence.parts;
  result->detections = std::move(mapped);
  result->object_mask_seconds = watch.Lap();
}

HybridResult HybridSegmenter::Run(
    const ColorImage& rgb, const Image<uint8_t>* prompt_region,
    std::optional<SemanticResult> semantic,
    const std::vector<detect::LabeledDetection>* detections) {
  // Below this the models see a few pixels blown up to their input size and
  // return noise; say so instead.
  constexpr int kMinSide = 16;
  CheckArgument(rgb.width() >= kMinSide && rgb.height() >= kMinSide,
                "image is " + std::to_string(rgb.width()) + "x" +
                    std::to_string(rgb.height()) +
                    " pixels; segmentation needs at least 16x16");
  HybridResult result;
  Stopwatch watch;
  result.semantic_branch =
      semantic ? std::move(*semantic) : semantic_->Segment(rgb);
  result.semantic_seconds = watch.Lap();
  if (masks_) {
    result.masks = prompt_region ? masks_->GenerateWhere(rgb, *prompt_region)
                                 : masks_->Generate(rgb);
    if (detector_) AddObjectEvidence(rgb, prompt_region, detections, &result);
    result.mask_stats = masks_->stats();
  }
  watch.Lap();  // the masks' time is in mask_stats
  result.vote =
      Vote(result.semantic_branch.labels, result.masks,
           result.mask_evidence.empty() ? nullptr : &result.mask_evidence,
           &semantic_->label_set());
  if (options_.objects.join_parts && !result.mask_detection.empty()) {
    result.mask_instance = JoinDetectedParts(
        result.detections, result.mask_detection, result.mask_part_of,
        &result.vote, &result.parts_joined);
  }
  result.vote_seconds = watch.Lap();
  return result;
}

}  // namespace semrec::segment
