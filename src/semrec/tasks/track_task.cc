#include "semrec/tasks/track_task.h"

#include <map>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/core/progress.h"
#include "semrec/io/mot_io.h"
#include "semrec/pipeline/track_images.h"
#include "semrec/segment/segment_io.h"
#include "semrec/track/tracker.h"

namespace fs = std::filesystem;

namespace semrec::tasks {
namespace {

TrackTaskResult TrackDetections(const TrackTaskOptions& options) {
  const auto by_frame =
      track::DetectionsByFrame(io::ReadMotFile(options.detections));
  TrackTaskResult result;
  for (const auto& [f, d] : by_frame) result.detections += d.size();
  const int frames = by_frame.empty() ? 0 : by_frame.rbegin()->first;
  track::Tracker tracker(options.people.tracker);
  Progress progress("tracking", static_cast<size_t>(frames));
  const auto points = track::TrackSequence(&tracker, by_frame, frames,
                                           [&] { progress.Tick(); });
  progress.Finish();
  const std::vector<io::MotBox> boxes =
      track::ToMotBoxes(track::FinishTracks(points, options.offline));
  io::WriteMotFile(options.out, boxes);
  result.frames = static_cast<size_t>(frames);
  result.boxes = boxes.size();
  return result;
}

// Images: detect (or read boxes), mask, embed, track; the result file,
// person instance PNGs, overlays and summary.json.
TrackTaskResult TrackImages(const infer::ModelRegistry& registry,
                            const TrackTaskOptions& options) {
  const track::PcaProjection pca =
      options.pca.empty() ? track::PcaProjection()
                          : track::PcaProjection::Load(options.pca);
  const auto inputs = segment::ListSegmentInputs(
      options.input.string(), options.stride, options.max_frames);
  std::map<int, std::vector<track::Detection>> given;
  if (!options.detections.empty()) {
    given = track::DetectionsByFrame(io::ReadMotFile(options.detections));
  }
  RequireEmptyOrOverwrite(options.out, options.overwrite);
  pipeline::TrackImagesOptions track_options;
  track_options.people = options.people;
  track_options.offline = options.offline;
  track_options.frame_step = options.stride;
  const pipeline::TrackImagesResult r = pipeline::TrackImages(
      registry, track_options, pca, inputs,
      options.detections.empty() ? nullptr : &given, options.out.string());
  const double n = inputs.empty() ? 1.0 : static_cast<double>(inputs.size());
  nlohmann::json summary = {
      {"input", options.input.string()},
      {"frames", inputs.size()},
      {"frame_step", options.stride},
      {"detections", options.detections.empty() ? options.people.detector.model
                                                : options.detections.string()},
      {"masks", options.masks_name},
      {"tracks", r.tracks},
      {"boxes", r.boxes.size()},
      {"reidentified", r.reidentified},
      {"reid", options.people.tracker.reid.enabled},
      {"tau", options.people.tracker.reid.tau},
      {"pca", options.pca.string()},
      {"seconds_per_frame",
       {{"detect", r.detect_seconds / n},
        {"encode", r.encode_seconds / n},
        {"masks", r.mask_seconds / n}}}};
  if (!options.fit_pca.empty()) {
    if (r.embeddings.size() < static_cast<size_t>(options.pca_dims) + 1) {
      throw InvalidArgument(fmt::format(
          "--fit-pca: only {} person embeddings in {}, need more than {}",
          r.embeddings.size(), options.input.string(), options.pca_dims));
    }
    const auto fitted = track::PcaProjection::Fit(
        r.embeddings, options.pca_dims, /*whiten=*/true);
    fitted.Save(options.fit_pca);
    summary["fitted_pca"] = {
        {"file", options.fit_pca.string()},
        {"embeddings", r.embeddings.size()},
        {"explained_variance", fitted.explained_variance()}};
  }
  WriteTextFileAtomic(options.out / "summary.json", summary.dump(2) + "\n");
  TrackTaskResult result;
  result.frames = inputs.size();
  result.tracks = r.tracks;
  result.boxes = r.boxes.size();
  result.reidentified = r.reidentified;
  return result;
}

}  // namespace

void TrackTaskOptions::Check() const {
  CheckArgument(
      !input.empty() || !detections.empty(),
      "track: give an image folder or sequence, or --detections det.txt");
  CheckArgument(!out.empty(), "track: no output given");
  CheckArgument(pca_dims >= 1, "track: pca_dims must be >= 1");
  CheckArgument(fit_pca.empty() || (!input.empty() && people.masks),
                "--fit-pca needs masks (embeddings): drop --masks none");
  CheckArgument(stride >= 1, "track: stride must be >= 1");
  if (input.empty()) {
    people.tracker.Check();
  } else {
    people.Check();
  }
  offline.Check();
}

TrackTaskResult RunTrackTask(const infer::ModelRegistry* registry,
                             const TrackTaskOptions& options) {
  options.Check();
  if (options.input.empty()) return TrackDetections(options);
  CheckArgument(registry != nullptr, "track: images need a model registry");
  return TrackImages(*registry, options);
}

}  // namespace semrec::tasks
