#include "semrec/track/tracker.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Core>

#include "semrec/core/error.h"
#include "semrec/track/hungarian.h"

namespace semrec::track {

void TrackerOptions::Check() const {
  CheckArgument(max_corner_cost_px >= 0.0,
                "tracker: max_corner_cost_px must be >= 0");
  CheckArgument(min_iou > 0.0 && min_iou <= 1.0,
                "tracker: min_iou must be in (0, 1]");
  CheckArgument(max_lost_frames >= 0, "tracker: max_lost_frames must be >= 0");
  CheckArgument(min_hits >= 1, "tracker: min_hits must be >= 1");
  reid.Check();
}

TrackerOptions TrackerOptions::Paper() {
  TrackerOptions o;
  o.max_corner_cost_px = 0.0;
  return o;
}

TrackerOptions TrackerOptions::Improved() {
  TrackerOptions o;
  o.cost = Cost::kIou;
  o.motion = Motion::kKalman;
  o.max_lost_frames = 10;
  o.min_score = 0.7;
  return o;
}

namespace {

void UpdateEmbedding(const std::vector<float>& observed, double weight,
                     std::vector<float>* running) {
  if (observed.empty()) return;
  if (running->size() != observed.size()) {
    *running = observed;
    return;
  }
  for (size_t i = 0; i < observed.size(); ++i) {
    (*running)[i] = static_cast<float>((1.0 - weight) * (*running)[i] +
                                       weight * observed[i]);
  }
}

}  // namespace

Tracker::Tracker(const TrackerOptions& options, PcaProjection pca)
    : options_(options), memory_(options.reid, std::move(pca)) {
  options_.Check();
}

std::vector<TrackedBox> Tracker::Update(
    const std::vector<Detection>& all_detections) {
  std::vector<Detection> detections;
  for (const Detection& d : all_detections) {
    if (d.score >= options_.min_score) detections.push_back(d);
  }
  // Candidate boxes: last box, moved by the velocity of the frames it was lost
  // for.
  std::vector<Box> predicted(tracks_.size());
  for (size_t t = 0; t < tracks_.size(); ++t) {
    predicted[t] = tracks_[t].box;
    if (options_.motion == TrackerOptions::Motion::kKalman) {
      predicted[t] = tracks_[t].filter.Predict();
    } else if (options_.motion == TrackerOptions::Motion::kVelocity) {
      const double steps = tracks_[t].lost_frames + 1;
      predicted[t].left += tracks_[t].vx * steps;
      predicted[t].top += tracks_[t].vy * steps;
    }
  }
  Eigen::MatrixXd cost(detections.size(), tracks_.size());
  for (size_t d = 0; d < detections.size(); ++d) {
    for (size_t t = 0; t < tracks_.size(); ++t) {
      if (options_.cost == TrackerOptions::Cost::kCorners) {
        const double c = CornerDistance(detections[d].box, predicted[t]);
        const bool gated = options_.max_corner_cost_px > 0.0 &&
                           c > options_.max_corner_cost_px;
        cost(d, t) = gated ? kForbidden : c;
      } else {
        const double iou = Iou(detections[d].box, predicted[t]);
        cost(d, t) = iou >= options_.min_iou ? 1.0 - iou : kForbidden;
      }
    }
  }
  std::vector<int> track_of(detections.size(), -1);
  for (const auto& [d, t] : SolveAssignment(cost).pairs) track_of[d] = t;

  // Re-identification of the detections geometry left unmatched.
  std::vector<int> reid_of(detections.size(), -1);
  if (options_.reid.enabled) {
    std::vector<size_t> unmatched;
    std::vector<std::vector<float>> queries;
    for (size_t d = 0; d < detections.size(); ++d) {
      if (track_of[d] < 0 && !detections[d].embedding.empty()) {
        unmatched.push_back(d);
        queries.push_back(detections[d].embedding);
      }
    }
    const std::vector<int> ids = memory_.Match(queries);
    for (size_t k = 0; k < unmatched.size(); ++k) {
      reid_of[unmatched[k]] = ids[k];
    }
  }

  // Only the Kalman motion model reads the filter: skip its updates otherwise.
  const bool kalman = options_.motion == TrackerOptions::Motion::kKalman;
  std::vector<char> matched(tracks_.size(), 0);
  std::vector<TrackedBox> out;
  std::vector<Track> born;
  for (size_t d = 0; d < detections.size(); ++d) {
    const Box& b = detections[d].box;
    if (track_of[d] >= 0) {
      Track& track = tracks_[track_of[d]];
      matched[track_of[d]] = 1;
      const double steps = track.lost_frames + 1;
      const double vx =
          (b.left + b.width / 2 - track.box.left - track.box.width / 2) / steps;
      const double vy =
          (b.top + b.height / 2 - track.box.top - track.box.height / 2) / steps;
      // Smoothed velocity (first observation takes the raw value).
      track.vx = track.age > 0 ? 0.5 * track.vx + 0.5 * vx : vx;
      track.vy = track.age > 0 ? 0.5 * track.vy + 0.5 * vy : vy;
      track.box = b;
      if (kalman) track.filter.Update(b);
      track.lost_frames = 0;
      UpdateEmbedding(detections[d].embedding, options_.reid.embedding_update,
                      &track.embedding);
      ++track.age;
      out.push_back({track.id, b, detections[d].score,
                     track.age + 1 >= options_.min_hits, false});
    } else {
      // A re-identified person continues the old track (confirmed already).
      const bool known = reid_of[d] >= 0;
      Track track;
      track.id = known ? reid_of[d] : next_id_++;
      track.box = b;
      if (kalman) track.filter = BoxFilter(b);
      track.embedding = detections[d].embedding;
      if (known) track.age = options_.min_hits;
      born.push_back(track);
      out.push_back({track.id, b, detections[d].score,
                     known || options_.min_hits <= 1, known});
    }
  }
  std::vector<Track> next;
  for (size_t t = 0; t < tracks_.size(); ++t) {
    if (!matched[t]) {
      ++tracks_[t].lost_frames;
      if (tracks_[t].lost_frames > options_.max_lost_frames) {
        memory_.Remember(tracks_[t].id, tracks_[t].embedding);
        continue;
      }
    }
    next.push_back(tracks_[t]);
  }
  for (Track& t : born) next.push_back(t);
  tracks_ = std::move(next);
  return out;
}

std::vector<int> Tracker::LostTrackIds() const {
  std::vector<int> ids;
  for (const Track& t : tracks_) {
    if (t.lost_frames > 0) ids.push_back(t.id);
  }
  return ids;
}

}  // namespace semrec::track
