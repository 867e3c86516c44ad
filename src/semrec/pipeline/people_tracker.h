// People tracking on images (the paper's Section II-B end to end): person
// detections (YOLOX, or given boxes) -> one mask per person from the mask
// decoder prompted with the box -> an appearance embedding per person (SAM2's
// object pointer, else the image embedding pooled under the mask) -> the
// tracker (Hungarian on box corners + re-identification of re-appearing
// people).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "semrec/core/image.h"
#include "semrec/core/label_map.h"
#include "semrec/detect/yolox_detector.h"
#include "semrec/infer/model_registry.h"
#include "semrec/segment/mask.h"
#include "semrec/segment/promptable.h"
#include "semrec/track/reid.h"
#include "semrec/track/tracker.h"

namespace semrec::pipeline {

struct PeopleTrackerOptions {
  /// Person detector (used when Process() gets no detections).
  detect::YoloxOptions detector;
  /// Box-prompted person masks and embeddings; off = boxes only (no
  /// re-identification, since there is no appearance).
  bool masks = true;
  segment::PromptableOptions mask_model;
  /// "auto": SAM2's object pointer when the decoder returns one, else the
  /// pooled image embedding; "pooled" forces the latter.
  std::string embedding = "auto";
  /// Geometry + re-identification. Default: the paper's configuration.
  track::TrackerOptions tracker = track::TrackerOptions::Paper();
  void Check() const;
};

struct PersonObservation {
  track::TrackedBox box;
  /// Empty (area 0) when masks are off.
  segment::Mask mask;
  std::vector<float> embedding;
};

struct PeopleFrame {
  std::vector<PersonObservation> people;
  double detect_seconds = 0.0;
  double encode_seconds = 0.0;
  double mask_seconds = 0.0;
  /// The detections (with embeddings) the tracker got: with Replay() they
  /// redo this frame's tracking without the models (checkpoint resume).
  std::vector<track::Detection> tracker_input;
};

class PeopleTracker {
 public:
  /// Loads the detector lazily (only when Process() must detect) and the mask
  /// model when masks are on. Throws as OnnxModel does for missing / corrupt
  /// models.
  PeopleTracker(const infer::ModelRegistry& registry,
                const PeopleTrackerOptions& options,
                track::PcaProjection pca = {});
  ~PeopleTracker();

  /// Tracks one frame. `detections` replaces the detector when given (public
  /// MOT detections, ground-truth boxes).
  PeopleFrame Process(
      const ColorImage& rgb,
      const std::optional<std::vector<track::Detection>>& detections = {});

  /// Advances the tracker as Process() did on a frame whose `tracker_input`
  /// this is, without running any model; returns the tracked boxes.
  std::vector<track::TrackedBox> Replay(
      const std::vector<track::Detection>& tracker_input);

 private:
  const infer::ModelRegistry& registry_;
  PeopleTrackerOptions options_;
  std::unique_ptr<detect::YoloxDetector> detector_;
  std::unique_ptr<segment::PromptableSegmenter> masks_;
  track::Tracker tracker_;
};

/// Paints the people's masks (track ids as labels, 0 = background) into one
/// 16-bit map; smaller masks are painted last so that a person in front of a
/// larger one stays visible. Without masks the boxes are filled.
LabelMap PersonInstanceMap(const std::vector<PersonObservation>& people,
                           int width, int height);

/// The image with each person's mask tinted and box outlined in a colour per
/// track id, the id written above the box.
ColorImage RenderPeopleOverlay(const ColorImage& rgb,
                               const std::vector<PersonObservation>& people);

}  // namespace semrec::pipeline
