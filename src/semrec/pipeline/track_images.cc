#include "semrec/pipeline/track_images.h"

#include <set>

#include "semrec/core/error.h"
#include "semrec/io/image_io.h"

namespace fs = std::filesystem;

namespace semrec::pipeline {

void TrackImagesOptions::Check() const {
  people.Check();
  offline.Check();
  CheckArgument(frame_step >= 1, "track: frame_step must be >= 1");
}

TrackImagesResult TrackImages(
    const infer::ModelRegistry& registry, const TrackImagesOptions& options,
    const track::PcaProjection& pca,
    const std::vector<segment::SegmentInput>& inputs,
    const std::map<int, std::vector<track::Detection>>* given,
    const fs::path& out_dir, const ProgressOptions& progress_options) {
  options.Check();
  PeopleTracker tracker(registry, options.people, pca);
  TrackImagesResult result;
  std::vector<track::TrackPoint> points;
  Progress progress("tracking", inputs.size(), progress_options);
  for (size_t i = 0; i < inputs.size(); ++i) {
    // The recording's frame number (MOTChallenge frames start at 1).
    const int frame_number = 1 + static_cast<int>(i) * options.frame_step;
    const ColorImage rgb = inputs[i].Load();
    std::optional<std::vector<track::Detection>> boxes;
    if (given != nullptr) {
      const auto it = given->find(frame_number);
      boxes = it == given->end() ? std::vector<track::Detection>{} : it->second;
    }
    PeopleFrame frame;
    try {
      frame = tracker.Process(rgb, boxes);
    } catch (const InvalidArgument& e) {
      throw FormatError(inputs[i].image, e.what());
    }
    result.detect_seconds += frame.detect_seconds;
    result.encode_seconds += frame.encode_seconds;
    result.mask_seconds += frame.mask_seconds;
    for (const auto& p : frame.people) {
      if (!p.embedding.empty()) result.embeddings.push_back(p.embedding);
      points.push_back({frame_number, p.box, false});
      result.reidentified += p.box.reidentified;
    }
    const fs::path name = inputs[i].name;
    io::WritePng(out_dir / "persons" / name,
                 PersonInstanceMap(frame.people, rgb.width(), rgb.height()));
    io::WritePng(out_dir / "overlay" / name,
                 RenderPeopleOverlay(rgb, frame.people));
    progress.Tick();
  }
  progress.Finish();
  // The per-frame images show the online state; the result file gets the
  // offline steps on the finished tracks. With a stride, the gaps between
  // sampled frames are no missed detections: the offline step works on
  // image numbers and the result is mapped back to frame numbers.
  for (auto& p : points) p.frame = 1 + (p.frame - 1) / options.frame_step;
  std::vector<track::TrackPoint> finished =
      track::FinishTracks(points, options.offline);
  for (auto& p : finished) p.frame = 1 + (p.frame - 1) * options.frame_step;
  result.boxes = track::ToMotBoxes(finished);
  std::set<int> ids;
  for (const io::MotBox& b : result.boxes) ids.insert(b.id);
  result.tracks = ids.size();
  io::WriteMotFile(out_dir / "result.txt", result.boxes);
  return result;
}

}  // namespace semrec::pipeline
