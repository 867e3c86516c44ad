#include "semrec/pipeline/map_guidance.h"

#include <algorithm>
#include <cmath>
#include <map>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "semrec/core/error.h"

namespace semrec::pipeline {
namespace {

Image<uint8_t> Filled(int w, int h, uint8_t value) {
  return Image<uint8_t>(w, h, 1, value);
}

// The connected regions (8-connected) of `mask` with at least min_region_px
// pixels, grown by region_margin_px; `kept_px` gets their size before growing.
Image<uint8_t> KeptRegions(const cv::Mat& mask,
                           const MapGuidanceOptions& options, size_t* kept_px) {
  cv::Mat labels, stats, centroids;
  const int n =
      cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8);
  std::vector<uint8_t> keep(static_cast<size_t>(n), 0);
  *kept_px = 0;
  for (int i = 1; i < n; ++i) {
    const int area = stats.at<int>(i, cv::CC_STAT_AREA);
    if (area >= options.min_region_px) {
      keep[static_cast<size_t>(i)] = 1;
      *kept_px += static_cast<size_t>(area);
    }
  }
  Image<uint8_t> region(mask.cols, mask.rows);
  for (int y = 0; y < mask.rows; ++y) {
    for (int x = 0; x < mask.cols; ++x) {
      region(x, y) = keep[static_cast<size_t>(labels.at<int>(y, x))];
    }
  }
  if (options.region_margin_px > 0) {
    const int k = 2 * options.region_margin_px + 1;
    cv::Mat view(mask.rows, mask.cols, CV_8U, region.data());
    cv::dilate(view, view,
               cv::getStructuringElement(cv::MORPH_RECT, cv::Size(k, k)));
  }
  return region;
}

double Share(size_t pixels, size_t valid) {
  return valid == 0 ? 1.0
                    : static_cast<double>(pixels) / static_cast<double>(valid);
}

}  // namespace

void MapGuidanceOptions::Check() const {
  CheckArgument(projection_only_below >= 0 && projection_only_below <= 1,
                "map guidance: projection_only_below must be in [0, 1]");
  CheckArgument(refresh_every >= 1, "map guidance: refresh_every must be >= 1");
  CheckArgument(
      refresh_angle_deg > 0 && refresh_distance_m > 0,
      "map guidance: refresh_angle_deg and refresh_distance_m must be > 0");
  CheckArgument(
      min_region_px >= 0 && region_margin_px >= 0,
      "map guidance: min_region_px and region_margin_px must be >= 0");
}

const char* FrameModeName(FrameMode mode) {
  switch (mode) {
    case FrameMode::kFull:
      return "full";
    case FrameMode::kPartial:
      return "partial";
    case FrameMode::kProjectionOnly:
      return "projection";
  }
  return "?";
}

const char* GuidanceReasonName(GuidanceReason reason) {
  switch (reason) {
    case GuidanceReason::kNoMapYet:
      return "no map yet";
    case GuidanceReason::kFirstFrame:
      return "first frame";
    case GuidanceReason::kRefresh:
      return "refresh";
    case GuidanceReason::kCameraMoved:
      return "camera moved";
    case GuidanceReason::kNewContent:
      return "new content";
    case GuidanceReason::kExplained:
      return "explained";
    case GuidanceReason::kDisagreement:
      return "disagreement";
  }
  return "?";
}

GuidanceDecision DecideFrame(const fuse::ProjectedMap& projected,
                             const Transform& T_world_camera,
                             const std::optional<Transform>& T_world_last_full,
                             size_t frames_since_full,
                             const MapGuidanceOptions& options,
                             const LabelMap* ignore) {
  options.Check();
  const int w = projected.state.width();
  const int h = projected.state.height();
  CheckArgument(
      ignore == nullptr || ignore->SameSize(w, h),
      "map guidance: the ignore mask's size differs from the frame's");
  GuidanceDecision d;
  const auto full = [&](GuidanceReason reason) {
    d.mode = FrameMode::kFull;
    d.reason = reason;
    d.prompt_region = Filled(w, h, 1);
    return d;
  };
  if (!T_world_last_full) return full(GuidanceReason::kFirstFrame);
  if (frames_since_full >= static_cast<size_t>(options.refresh_every)) {
    return full(GuidanceReason::kRefresh);
  }
  const Transform motion = T_world_last_full->Inverse() * T_world_camera;
  if (motion.AngleDeg() > options.refresh_angle_deg ||
      motion.translation().norm() > options.refresh_distance_m) {
    return full(GuidanceReason::kCameraMoved);
  }

  // Unexplained: valid depth, not explained by the map (contradicted pixels
  // included: what is there now must be segmented anew).
  cv::Mat unexplained(h, w, CV_8U, cv::Scalar(0));
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const uint8_t state = projected.state(x, y);
      unexplained.at<uint8_t>(y, x) =
          (state == fuse::ProjectedMap::kUnexplained ||
           state == fuse::ProjectedMap::kContradicted) &&
                  (ignore == nullptr || (*ignore)(x, y) == 0)
              ? 1
              : 0;
    }
  }
  size_t unexplained_px = 0;
  Image<uint8_t> region = KeptRegions(unexplained, options, &unexplained_px);
  d.unexplained_share = Share(unexplained_px, projected.valid_depth_pixels);
  if (d.unexplained_share < options.projection_only_below) {
    d.mode = FrameMode::kProjectionOnly;
    d.reason = GuidanceReason::kExplained;
    d.prompt_region = Filled(w, h, 0);
    return d;
  }
  d.mode = FrameMode::kPartial;
  d.reason = GuidanceReason::kNewContent;
  d.prompt_region = std::move(region);
  return d;
}

double AddDisagreement(const fuse::ProjectedMap& projected,
                       const LabelMap& semantic,
                       const MapGuidanceOptions& options,
                       GuidanceDecision* decision) {
  options.Check();
  const int w = projected.state.width();
  const int h = projected.state.height();
  CheckArgument(
      semantic.SameSize(w, h) && decision->prompt_region.SameSize(w, h),
      "map guidance: the semantic labels' or the prompt region's "
      "size differs from the projected map's");
  if (decision->mode == FrameMode::kFull) return 0.0;
  cv::Mat disagree(h, w, CV_8U, cv::Scalar(0));
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      disagree.at<uint8_t>(y, x) =
          projected.state(x, y) == fuse::ProjectedMap::kExplained &&
                  semantic(x, y) != projected.class_id(x, y)
              ? 1
              : 0;
    }
  }
  // Semantic borders are blurred: a band of a few pixels along every
  // silhouette disagrees; only areas count.
  cv::morphologyEx(disagree, disagree, cv::MORPH_OPEN,
                   cv::getStructuringElement(cv::MORPH_RECT, cv::Size(5, 5)));
  size_t disagree_px = 0;
  Image<uint8_t> region = KeptRegions(disagree, options, &disagree_px);
  if (disagree_px == 0) return 0.0;
  for (size_t p = 0; p < region.NumPixels(); ++p) {
    decision->prompt_region.data()[p] |= region.data()[p];
  }
  decision->override_region = std::move(region);
  if (decision->mode == FrameMode::kProjectionOnly) {
    decision->mode = FrameMode::kPartial;
    decision->reason = GuidanceReason::kDisagreement;
  }
  return Share(disagree_px, projected.valid_depth_pixels);
}

fuse::FrameLabels ComposeFrameLabels(const fuse::ProjectedMap& projected,
                                     const GuidanceDecision& decision,
                                     const segment::VoteResult* fresh,
                                     const std::string& source) {
  const int w = projected.state.width();
  const int h = projected.state.height();
  CheckArgument(decision.prompt_region.SameSize(w, h),
                "map guidance: the prompt region's size differs from the "
                "projected map's");
  CheckArgument(decision.mode == FrameMode::kProjectionOnly || fresh != nullptr,
                std::string("map guidance: a ") + FrameModeName(decision.mode) +
                    " frame needs the fresh segmentation");
  if (fresh != nullptr) {
    CheckArgument(
        fresh->semantic.SameSize(w, h) && fresh->instance.SameSize(w, h),
        "map guidance: the fresh segmentation's size differs from the frame's");
  }
  if (decision.mode == FrameMode::kFull) {
    return {fresh->instance, fresh->semantic, source};
  }
  fuse::FrameLabels labels{LabelMap(w, h), LabelMap(w, h), source};
  // Fresh instances keep their ids; map objects follow them, in id order.
  uint32_t next_id = 1;
  if (fresh != nullptr) {
    for (const uint16_t v : fresh->instance.values()) {
      next_id = std::max<uint32_t>(next_id, uint32_t{v} + 1);
    }
  }
  std::map<uint32_t, uint16_t> instance_of_object;
  for (size_t p = 0; p < projected.state.NumPixels(); ++p) {
    if (projected.state.data()[p] == fuse::ProjectedMap::kExplained) {
      instance_of_object.emplace(projected.object_id.data()[p], 0);
    }
  }
  for (auto& [object_id, instance] : instance_of_object) {
    CheckArgument(next_id <= 65535,
                  "map guidance: more than 65535 instances in one frame");
    instance = static_cast<uint16_t>(next_id++);
    labels.map_objects[instance] = object_id;
  }
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const bool fresh_wins = fresh != nullptr &&
                              !decision.override_region.empty() &&
                              decision.override_region(x, y) != 0;
      if (projected.state(x, y) == fuse::ProjectedMap::kExplained &&
          !fresh_wins) {
        labels.instance(x, y) =
            instance_of_object.at(projected.object_id(x, y));
        labels.semantic(x, y) = projected.class_id(x, y);
      } else if (fresh != nullptr && decision.prompt_region(x, y) != 0) {
        labels.instance(x, y) = fresh->instance(x, y);
        labels.semantic(x, y) = fresh->semantic(x, y);
      }
    }
  }
  return labels;
}

ColorImage RenderGuidanceOverlay(const ColorImage& overlay,
                                 const GuidanceDecision& decision) {
  ColorImage out = overlay;
  const int w = out.width(), h = out.height();
  cv::Mat canvas(h, w, CV_8UC3, out.data());
  if (decision.mode == FrameMode::kPartial &&
      decision.prompt_region.SameSize(w, h)) {
    cv::Mat region(h, w, CV_8U,
                   const_cast<uint8_t*>(decision.prompt_region.data()));
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(region.clone(), contours, cv::RETR_EXTERNAL,
                     cv::CHAIN_APPROX_SIMPLE);
    cv::drawContours(canvas, contours, -1, cv::Scalar(255, 220, 0), 2,
                     cv::LINE_AA);
  }
  const std::string text = std::string("map: ") + FrameModeName(decision.mode);
  const double scale = std::max(0.4, h / 960.0);
  const cv::Point at(6, 6 + static_cast<int>(24 * scale));
  cv::putText(canvas, text, at, cv::FONT_HERSHEY_SIMPLEX, scale,
              cv::Scalar(0, 0, 0), 3, cv::LINE_AA);
  cv::putText(canvas, text, at, cv::FONT_HERSHEY_SIMPLEX, scale,
              cv::Scalar(255, 220, 0), 1, cv::LINE_AA);
  return out;
}

}  // namespace semrec::pipeline
