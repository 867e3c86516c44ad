#include "semrec/pipeline/people_tracker.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <tbb/parallel_for.h>
#include <opencv2/imgproc.hpp>

#include "semrec/core/error.h"
#include "semrec/core/label_map.h"
#include "semrec/core/stopwatch.h"
#include "semrec/segment/detector_votes.h"

namespace semrec::pipeline {
namespace {}  // namespace

void PeopleTrackerOptions::Check() const {
  detector.Check();
  if (masks) mask_model.Check();
  CheckArgument(embedding == "auto" || embedding == "pooled",
                "people tracker: embedding must be 'auto' or 'pooled', got '" +
                    embedding + "'");
  tracker.Check();
}

PeopleTracker::PeopleTracker(const infer::ModelRegistry& registry,
                             const PeopleTrackerOptions& options,
                             track::PcaProjection pca)
    : registry_(registry),
      options_(options),
      tracker_(options.tracker, std::move(pca)) {
  options_.Check();
  if (options_.masks) {
    masks_ =
        segment::PromptableSegmenter::Create(registry_, options_.mask_model);
  }
}

PeopleTracker::~PeopleTracker() = default;

PeopleFrame PeopleTracker::Process(
    const ColorImage& rgb,
    const std::optional<std::vector<track::Detection>>& given) {
  PeopleFrame frame;
  Stopwatch watch;
  std::vector<track::Detection> detections;
  if (given) {
    detections = *given;
  } else {
    if (!detector_) {
      detector_ =
          std::make_unique<detect::YoloxDetector>(registry_, options_.detector);
    }
    for (const auto& d : detector_->Detect(rgb)) {
      detections.push_back({.box = d.box, .score = d.score, .embedding = {}});
    }
  }
  frame.detect_seconds = watch.Lap();

  std::vector<segment::Mask> masks(detections.size());
  if (masks_ && !detections.empty()) {
    masks_->SetImage(rgb);
    frame.encode_seconds = watch.Lap();
    tbb::parallel_for(static_cast<size_t>(0), detections.size(), [&](size_t i) {
      segment::Prompt prompt;
      prompt.box =
          segment::PromptBox(detections[i].box, rgb.width(), rgb.height());
      const segment::LowResMask low = masks_->Decode(prompt);
      masks[i] = masks_->Upsample(low);
      if (options_.embedding == "auto" && !low.object_pointer.empty()) {
        detections[i].embedding = low.object_pointer;
      } else if (masks[i].area > 0) {
        detections[i].embedding = masks_->PooledEmbedding(masks[i]);
      }
    });
    frame.mask_seconds = watch.Lap();
  }

  // The tracker skips low-score detections and keeps the others in order:
  // pair its output with the masks by walking the kept detections.
  const std::vector<track::TrackedBox> tracked = tracker_.Update(detections);
  frame.tracker_input = detections;
  size_t next = 0;
  for (const track::TrackedBox& t : tracked) {
    while (next < detections.size() &&
           detections[next].score < options_.tracker.min_score) {
      ++next;
    }
    CheckArgument(next < detections.size(), "people tracker: internal error");
    PersonObservation person;
    person.box = t;
    person.mask = std::move(masks[next]);
    person.embedding = std::move(detections[next].embedding);
    frame.people.push_back(std::move(person));
    ++next;
  }
  return frame;
}

std::vector<track::TrackedBox> PeopleTracker::Replay(
    const std::vector<track::Detection>& tracker_input) {
  return tracker_.Update(tracker_input);
}

LabelMap PersonInstanceMap(const std::vector<PersonObservation>& people,
                           int width, int height) {
  LabelMap map(width, height);
  std::vector<size_t> order(people.size());
  std::iota(order.begin(), order.end(), 0);
  const auto area = [&](size_t i) {
    const auto& p = people[i];
    return p.mask.area > 0 ? static_cast<double>(p.mask.area)
                           : p.box.box.width * p.box.box.height;
  };
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return area(a) > area(b); });
  for (size_t i : order) {
    const PersonObservation& p = people[i];
    const uint16_t id =
        static_cast<uint16_t>(std::clamp(p.box.track_id, 1, 65535));
    if (p.mask.area > 0) {
      const segment::Box& b = p.mask.box;
      for (int y = b.y0; y < b.y1; ++y) {
        for (int x = b.x0; x < b.x1; ++x) {
          if (p.mask.Contains(x, y)) map(x, y) = id;
        }
      }
    } else {
      const segment::Box b = segment::PromptBox(p.box.box, width, height);
      for (int y = b.y0; y < b.y1; ++y) {
        for (int x = b.x0; x < b.x1; ++x) map(x, y) = id;
      }
    }
  }
  return map;
}

ColorImage RenderPeopleOverlay(const ColorImage& rgb,
                               const std::vector<PersonObservation>& people) {
  const LabelMap ids = PersonInstanceMap(people, rgb.width(), rgb.height());
  ColorImage out = rgb;
  for (int y = 0; y < rgb.height(); ++y) {
    for (int x = 0; x < rgb.width(); ++x) {
      if (ids(x, y) == 0) continue;
      const auto color = LabelColor(ids(x, y));
      for (int c = 0; c < 3; ++c) {
        out(x, y, c) = static_cast<uint8_t>((rgb(x, y, c) + color[c]) / 2);
      }
    }
  }
  cv::Mat canvas(rgb.height(), rgb.width(), CV_8UC3, out.data());
  const double scale = std::clamp(rgb.width() / 1200.0, 0.4, 1.0);
  for (const PersonObservation& p : people) {
    const auto color = LabelColor(static_cast<uint32_t>(p.box.track_id));
    const cv::Scalar c(color[0], color[1], color[2]);  // RGB buffer
    const track::Box& b = p.box.box;
    cv::rectangle(canvas,
                  cv::Point(static_cast<int>(b.left), static_cast<int>(b.top)),
                  cv::Point(static_cast<int>(b.left + b.width),
                            static_cast<int>(b.top + b.height)),
                  c, 2);
    const std::string text = std::to_string(p.box.track_id);
    const cv::Point at(static_cast<int>(b.left),
                       std::max(12, static_cast<int>(b.top) - 4));
    cv::putText(canvas, text, at, cv::FONT_HERSHEY_SIMPLEX, scale,
                cv::Scalar(0, 0, 0), 3, cv::LINE_AA);
    cv::putText(canvas, text, at, cv::FONT_HERSHEY_SIMPLEX, scale, c, 1,
                cv::LINE_AA);
  }
  return out;
}

}  // namespace semrec::pipeline
