// The hybrid segmenter: semantic branch + mask branch + vote.
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include "semrec/detect/yolox_detector.h"
#include "semrec/segment/detector_votes.h"
#include "semrec/segment/mask_generator.h"
#include "semrec/segment/semantic_segmenter.h"
#include "semrec/segment/vote.h"

namespace semrec::segment {

struct HybridSegmenterOptions {
  SemanticSegmenterOptions semantic;
  /// Without masks the result is the semantic branch alone (instance map all
  /// 0).
  bool use_masks = true;
  MaskGeneratorOptions masks;
  /// Object detections as a second source of class evidence (off unless
  /// objects.model is set; needs masks).
  ObjectDetectorOptions objects;
  void Check() const;
};

struct HybridResult {
  /// The semantic branch's own output.
  SemanticResult semantic_branch;
  /// Masks (largest first) with their voted classes in `vote.mask_labels`.
  std::vector<Mask> masks;
  /// Final semantic and instance maps.
  VoteResult vote;
  MaskGeneratorStats mask_stats;
  /// Object detections used (label-set classes); per mask the detection it
  /// matched or came from (-1: none) and the class weights it added.
  std::vector<ObjectDetection> detections;
  std::vector<int> mask_detection;
  std::vector<MaskEvidence> mask_evidence;
  int detections_matched = 0;
  int detections_added = 0;
  int detection_parts = 0;
  /// Per mask: the detection holding it as a part (-1: none), and its
  /// instance id in vote.instance (i + 1 unless joined into its object's
  /// largest mask: ObjectDetectorOptions::join_parts); masks joined.
  std::vector<int> mask_part_of;
  std::vector<uint16_t> mask_instance;
  int parts_joined = 0;
  double semantic_seconds = 0;
  /// Detector (0 when detections were given) and the box prompts' masks.
  double detect_seconds = 0;
  double object_mask_seconds = 0;
  double vote_seconds = 0;
};

class HybridSegmenter {
 public:
  HybridSegmenter(const infer::ModelRegistry& registry,
                  const HybridSegmenterOptions& options);
  /// `detections` (the detector's raw output on this image, e.g. shared with
  /// people tracking) replace running the object detector; ignored when it
  /// is off.
  HybridResult Segment(
      const ColorImage& rgb,
      const std::vector<detect::LabeledDetection>* detections = nullptr);
  /// The semantic branch alone (map guidance looks at its labels before it
  /// chooses where to prompt).
  SemanticResult SegmentSemantic(const ColorImage& rgb);
  /// Segment() with mask prompts only where `prompt_region` is non-zero (map
  /// guidance: where the map cannot explain the frame); the semantic branch
  /// still sees the whole image (or its given result, from SegmentSemantic),
  /// so pixels outside every mask keep its label. Throws InvalidArgument when
  /// the region's or the given labels' size differs from the image's.
  /// Detections are used only where their box's centre lies in the region.
  HybridResult SegmentWhere(
      const ColorImage& rgb, const Image<uint8_t>& prompt_region,
      std::optional<SemanticResult> semantic = std::nullopt,
      const std::vector<detect::LabeledDetection>* detections = nullptr);
  const LabelSet& label_set() const { return semantic_->label_set(); }

  /// Whether the object detector is on, its registry name and options.
  bool detects_objects() const { return detector_ != nullptr; }
  const ObjectDetectorOptions& object_options() const {
    return options_.objects;
  }
  /// The object detector's raw output (every class, at its score
  /// threshold). Throws InvalidArgument when it is off.
  std::vector<detect::LabeledDetection> DetectObjects(
      const ColorImage& rgb) const;

 private:
  HybridResult Run(const ColorImage& rgb, const Image<uint8_t>* prompt_region,
                   std::optional<SemanticResult> semantic,
                   const std::vector<detect::LabeledDetection>* detections);
  void AddObjectEvidence(
      const ColorImage& rgb, const Image<uint8_t>* prompt_region,
      const std::vector<detect::LabeledDetection>* detections,
      HybridResult* result);

  HybridSegmenterOptions options_;
  std::unique_ptr<SemanticSegmenter> semantic_;
  std::unique_ptr<MaskGenerator> masks_;
  std::unique_ptr<detect::YoloxDetector> detector_;
  DetectorClassMap class_map_;
};

}  // namespace semrec::segment
