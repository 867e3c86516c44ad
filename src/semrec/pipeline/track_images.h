// Tracking people through a list of images (the `semrec track` command on
// images): detect (or take given boxes), box-prompted masks, embeddings,
// tracking with re-identification; person id maps and overlays per image, the
// offline-smoothed result file and a summary.
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <vector>

#include <nlohmann/json.hpp>

#include "semrec/core/progress.h"
#include "semrec/infer/model_registry.h"
#include "semrec/io/mot_io.h"
#include "semrec/pipeline/people_tracker.h"
#include "semrec/segment/segment_io.h"
#include "semrec/track/sequence.h"

namespace semrec::pipeline {

struct TrackImagesOptions {
  PeopleTrackerOptions people;
  track::OfflineOptions offline = track::OfflineOptions::Improved();
  /// Frame numbers (MOTChallenge, 1-based) of the images: image k is frame
  /// 1 + k * frame_step, so that with a stride the boxes of given detections
  /// and the result keep the recording's frame numbers.
  int frame_step = 1;
  void Check() const;
};

struct TrackImagesResult {
  /// Offline-smoothed boxes (result.txt).
  std::vector<io::MotBox> boxes;
  size_t tracks = 0;
  int reidentified = 0;
  /// Every person embedding seen (for fitting a PCA).
  std::vector<std::vector<float>> embeddings;
  double detect_seconds = 0.0, encode_seconds = 0.0, mask_seconds = 0.0;
};

/// Tracks people through `inputs`, writing `out_dir`/persons/<name> (16-bit
/// track ids), overlay/<name> and result.txt. `given`: boxes per frame number
/// instead of the detector (nullptr: detect).
TrackImagesResult TrackImages(
    const infer::ModelRegistry& registry, const TrackImagesOptions& options,
    const track::PcaProjection& pca,
    const std::vector<segment::SegmentInput>& inputs,
    const std::map<int, std::vector<track::Detection>>* given,
    const std::filesystem::path& out_dir, const ProgressOptions& progress = {});

}  // namespace semrec::pipeline
