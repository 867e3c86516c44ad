#include "semrec/track/sequence.h"

#include <algorithm>
#include <set>

#include "semrec/core/error.h"

namespace semrec::track {

void OfflineOptions::Check() const {
  CheckArgument(max_gap_frames >= 0, "tracker: max_gap_frames must be >= 0");
  CheckArgument(min_track_frames >= 1,
                "tracker: min_track_frames must be >= 1");
}

bool OfflineOptions::Off() const {
  return !backfill_tentative && max_gap_frames == 0 && min_track_frames <= 1;
}

OfflineOptions OfflineOptions::Improved() {
  OfflineOptions o;
  o.backfill_tentative = true;
  o.max_gap_frames = 10;
  o.min_track_frames = 3;
  return o;
}

std::map<int, std::vector<Detection>> DetectionsByFrame(
    const std::vector<io::MotBox>& boxes) {
  std::map<int, std::vector<Detection>> by_frame;
  for (const io::MotBox& b : boxes) {
    by_frame[b.frame].push_back(
        {{b.left, b.top, b.width, b.height}, b.confidence, {}});
  }
  return by_frame;
}

std::vector<io::MotBox> ToMotBoxes(const std::vector<TrackPoint>& points) {
  std::vector<io::MotBox> out;
  out.reserve(points.size());
  for (const TrackPoint& p : points) {
    const Box& b = p.box.box;
    out.push_back({p.frame, p.box.track_id, b.left, b.top, b.width, b.height,
                   p.box.score});
  }
  return out;
}

std::vector<TrackPoint> TrackSequence(
    Tracker* tracker, const std::map<int, std::vector<Detection>>& by_frame,
    int last_frame, const std::function<void()>& tick) {
  std::vector<TrackPoint> points;
  const std::vector<Detection> none;
  for (int f = 1; f <= last_frame; ++f) {
    const auto it = by_frame.find(f);
    for (const TrackedBox& t :
         tracker->Update(it == by_frame.end() ? none : it->second)) {
      points.push_back({f, t, false});
    }
    if (tick) tick();
  }
  return points;
}

namespace {

Box Lerp(const Box& a, const Box& b, double s) {
  return {a.left + s * (b.left - a.left), a.top + s * (b.top - a.top),
          a.width + s * (b.width - a.width),
          a.height + s * (b.height - a.height)};
}

}  // namespace

std::vector<TrackPoint> FinishTracks(const std::vector<TrackPoint>& points,
                                     const OfflineOptions& options) {
  options.Check();
  // Per track, its observed boxes in frame order.
  std::map<int, std::vector<TrackPoint>> tracks;
  std::set<int> confirmed;
  for (const TrackPoint& p : points) {
    tracks[p.box.track_id].push_back(p);
    if (p.box.confirmed) confirmed.insert(p.box.track_id);
  }
  std::vector<TrackPoint> out;
  for (auto& [id, track] : tracks) {
    if (!confirmed.count(id)) continue;
    if (static_cast<int>(track.size()) < options.min_track_frames) continue;
    std::stable_sort(track.begin(), track.end(),
                     [](const TrackPoint& a, const TrackPoint& b) {
                       return a.frame < b.frame;
                     });
    const TrackPoint* reported = nullptr;  // the last box output
    for (const TrackPoint& p : track) {
      if (!p.box.confirmed && !options.backfill_tentative) continue;
      // Gaps are filled between reported boxes only, and never across a
      // re-identification (the person left the view and came back).
      if (reported != nullptr && options.max_gap_frames > 0 &&
          !p.box.reidentified) {
        const TrackPoint& prev = *reported;
        const int gap = p.frame - prev.frame - 1;
        if (gap > 0 && gap <= options.max_gap_frames) {
          for (int g = 1; g <= gap; ++g) {
            TrackPoint fill = p;
            fill.frame = prev.frame + g;
            fill.box.box = Lerp(prev.box.box, p.box.box,
                                static_cast<double>(g) / (gap + 1));
            fill.box.score = std::min(prev.box.score, p.box.score);
            fill.box.confirmed = true;
            fill.interpolated = true;
            out.push_back(fill);
          }
        }
      }
      TrackPoint kept = p;
      kept.box.confirmed = true;
      out.push_back(kept);
      reported = &p;
    }
  }
  std::stable_sort(
      out.begin(), out.end(), [](const TrackPoint& a, const TrackPoint& b) {
        return a.frame != b.frame ? a.frame < b.frame
                                  : a.box.track_id < b.box.track_id;
      });
  return out;
}

}  // namespace semrec::track
