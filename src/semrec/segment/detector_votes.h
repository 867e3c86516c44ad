// Object detections as a second source of class evidence for the vote: a
// pixel classifier at 512x512 sees texture, a detector sees the whole object.
// Each detection of a class the label set can express becomes a
// box prompt; generated masks that match its mask, or lie inside it, receive
// the detector's class weighted by its score; a detection no mask matches
// adds its own mask.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "semrec/core/label_map.h"
#include "semrec/detect/yolox_detector.h"
#include "semrec/infer/onnx_model.h"
#include "semrec/segment/mask.h"
#include "semrec/segment/promptable.h"

namespace semrec::segment {

struct ObjectDetectorOptions {
  /// Detector registry name (role detector, e.g. "yolox_nano"); empty = off.
  std::string model;
  /// Detections below this score are ignored (YOLOX's objectness x class).
  float score_threshold = 0.3f;
  /// JSON map from detector class names to label-set class names ("couch":
  /// "sofa"; classes without a counterpart are left out). Empty: the data
  /// file class_maps/<detector set>_to_<label set>.json.
  std::string class_map;
  /// A matched detection adds weight x score to its class's share of the
  /// mask's semantic pixels (shares sum to 1). 1: a detection with score s
  /// turns a mask whose semantic winner leads the detected class by less than
  /// s.
  float weight = 1.0f;
  /// A generated mask matches a detection's box-prompted mask at this IoU.
  float match_iou = 0.5f;
  /// A smaller generated mask with at least this share of its pixels inside
  /// a detection's mask is a part of the object (a chair's seat and back)
  /// and receives the evidence scaled by that share (stuff does not yield
  /// there); 0 = parts get none.
  float part_containment = 0.8f;
  /// A detection that no generated mask matches adds its own mask when the
  /// decoder's predicted IoU for it is at least this (SAM's grid filter is
  /// 0.88; the one added mask below 0.9 seen on the samples, 0.887, was a
  /// distant car bleeding into the road; chess's desks and chairs: >= 0.95).
  float min_predicted_iou = 0.9f;
  /// In a mask that matches a detection (or is added for it), the pixel
  /// shares of stuff classes (wall, floor, road...) are scaled by 1 - score:
  /// a mask shaped like the detected object is that object, however much of
  /// it the pixel classifier called wall. false = only the added weight.
  bool stuff_yields = true;
  /// After the vote, the masks of one detected object that voted its class
  /// (the matched or added mask and its parts: a chair's seat, back and legs,
  /// which a mask generator cuts apart in most views, the same way each time)
  /// become one instance. Parts that voted another class (a cup on a detected
  /// table) stay apart.
  bool join_parts = true;
  /// Threads, provider of the detector.
  infer::OnnxModelOptions runtime;
  bool enabled() const { return !model.empty(); }
  void Check() const;
};

/// A detection in the label set's classes.
struct ObjectDetection {
  Box box;
  uint16_t class_id = 0;   // label-set id
  int detector_class = 0;  // the detector's own class id
  float score = 0.0f;
};

/// Detector class ids -> label-set ids, from a JSON object of class names.
class DetectorClassMap {
 public:
  DetectorClassMap() = default;
  /// Reads {"detector class": "label class", ...} ("_comment" keys ignored).
  /// Throws FormatError naming the file for a name either set lacks or a
  /// value that is not a string.
  static DetectorClassMap Load(const std::filesystem::path& path,
                               const LabelSet& detector_classes,
                               const LabelSet& label_set);
  /// The default file for two label-set names (registry spelling, e.g.
  /// coco80 and ade20k-top31) in the project's data folder.
  static std::filesystem::path DefaultPath(const std::string& detector_set,
                                           const std::string& label_set);
  std::optional<uint16_t> Map(int detector_class) const;
  size_t size() const { return map_.size(); }

 private:
  std::map<int, uint16_t> map_;
};

/// A detector's box (pixels, fractional) rounded and clipped to a
/// width x height image, as a box prompt.
Box PromptBox(const detect::Box& box, int width, int height);

/// Detections of mapped classes with score >= min_score, boxes clipped to
/// the image (empty boxes dropped), in the given order.
std::vector<ObjectDetection> MapDetections(
    const std::vector<detect::LabeledDetection>& detections,
    const DetectorClassMap& class_map, float min_score, int width, int height);

/// Box-prompted masks of `detections` on the image `model` holds, one per
/// detection in order (predicted IoU set; empty when the decoder finds
/// nothing), small islands and holes cleaned as the grid's masks are.
std::vector<Mask> DecodeDetectionMasks(
    const PromptableSegmenter& model,
    const std::vector<ObjectDetection>& detections, int min_region_area_px);

/// Extra class weight for one mask.
struct ClassWeight {
  uint16_t class_id = 0;
  float weight = 0.0f;
};

/// What the vote adds to one mask's pixel shares.
struct MaskEvidence {
  std::vector<ClassWeight> weights;
  /// Factor on the pixel shares of stuff classes (1 = unchanged).
  float stuff_scale = 1.0f;
  bool empty() const { return weights.empty() && stuff_scale == 1.0f; }
};

struct ObjectEvidence {
  /// The masks, with added detection masks, sorted by area (largest first).
  std::vector<Mask> masks;
  /// Per mask: the detector's evidence (empty for most).
  std::vector<MaskEvidence> evidence;
  /// Per mask: the detection it matched or came from (-1: none).
  std::vector<int> detection;
  /// Per mask: the detection whose mask holds it as a part (-1: none; of
  /// several, the one holding most of it).
  std::vector<int> part_of;
  int matched = 0;  // detections a generated mask matched
  int parts = 0;    // generated masks that took evidence as a part
  int added = 0;    // detections that added their own mask
};

/// Attaches `detections` (with their masks from DecodeDetectionMasks, same
/// order) to the generated `masks`: each detection goes to the generated
/// mask of the highest IoU >= match_iou; generated masks mostly inside a
/// detection's mask take it as parts; an unmatched detection with a good
/// mask is added. Throws InvalidArgument when the lists' sizes differ.
ObjectEvidence AttachDetections(std::vector<Mask> masks,
                                const std::vector<ObjectDetection>& detections,
                                std::vector<Mask> detection_masks,
                                const ObjectDetectorOptions& options);

struct VoteResult;  // segment/vote.h

/// Joins the masks of each detected object that voted its class into one
/// instance (ObjectDetectorOptions::join_parts): in `vote->instance` their
/// pixels take the id of the largest of them. `mask_detection` and
/// `part_of` as in ObjectEvidence. Returns each mask's instance id after the
/// join (mask i was i + 1) and counts the masks joined into another in
/// `joined`.
std::vector<uint16_t> JoinDetectedParts(
    const std::vector<ObjectDetection>& detections,
    const std::vector<int>& mask_detection, const std::vector<int>& part_of,
    VoteResult* vote, int* joined);

}  // namespace semrec::segment
