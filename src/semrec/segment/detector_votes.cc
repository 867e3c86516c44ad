#include "semrec/segment/detector_votes.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <tbb/parallel_for.h>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/core/union_find.h"
#include "semrec/io/json_file.h"
#include "semrec/segment/mask_generator.h"
#include "semrec/segment/vote.h"

namespace semrec::segment {

void ObjectDetectorOptions::Check() const {
  if (!enabled()) return;
  const auto unit = [](float v) { return v >= 0 && v <= 1; };
  CheckArgument(unit(score_threshold),
                "object detector: score_threshold must be in [0, 1]");
  CheckArgument(weight >= 0 && std::isfinite(weight),
                "object detector: weight must be >= 0");
  CheckArgument(match_iou > 0 && match_iou <= 1,
                "object detector: match_iou must be in (0, 1]");
  CheckArgument(unit(part_containment),
                "object detector: part_containment must be in [0, 1]");
  CheckArgument(min_predicted_iou >= 0,
                "object detector: min_predicted_iou must be >= 0 (above 1: "
                "never add a detection's own mask)");
  runtime.Check();
}

DetectorClassMap DetectorClassMap::Load(const std::filesystem::path& path,
                                        const LabelSet& detector_classes,
                                        const LabelSet& label_set) {
  const nlohmann::json j = io::ReadJsonFile(path);
  if (!j.is_object()) {
    throw FormatError(path, "a class map must be a JSON object of names");
  }
  DetectorClassMap map;
  for (const auto& [from, to] : j.items()) {
    if (from.starts_with("_")) continue;  // _comment
    if (!to.is_string()) {
      throw FormatError(path, "'" + from + "' must map to a class name");
    }
    const auto source = detector_classes.FindByName(from);
    if (!source) {
      throw FormatError(
          path, "'" + from + "' is not a class of " + detector_classes.name());
    }
    const auto target = label_set.FindByName(to.get<std::string>());
    if (!target) {
      throw FormatError(path, "'" + to.get<std::string>() +
                                  "' is not a class of " + label_set.name());
    }
    map.map_[*source] = *target;
  }
  return map;
}

std::filesystem::path DetectorClassMap::DefaultPath(
    const std::string& detector_set, const std::string& label_set) {
  // One file per pair whatever alias a registry entry uses.
  static const std::map<std::string, std::string> kCanonical = {
      {"voc", "voc21"},
      {"ade20k", "ade20k150"},
      {"coco", "coco80"},
      {"ade20k_top31", "ade20k-top31"},
      {"cityscapes", "cityscapes19"}};
  const auto canonical = [](const std::string& name) {
    const auto it = kCanonical.find(name);
    return it == kCanonical.end() ? name : it->second;
  };
  return ProjectDataDir() / "class_maps" /
         (canonical(detector_set) + "_to_" + canonical(label_set) + ".json");
}

std::optional<uint16_t> DetectorClassMap::Map(int detector_class) const {
  const auto it = map_.find(detector_class);
  if (it == map_.end()) return std::nullopt;
  return it->second;
}

Box PromptBox(const detect::Box& b, int width, int height) {
  const auto clip = [](double v, int hi) {
    return std::clamp(static_cast<int>(std::lround(v)), 0, hi);
  };
  return {clip(b.left, width), clip(b.top, height),
          clip(b.left + b.width, width), clip(b.top + b.height, height)};
}

std::vector<ObjectDetection> MapDetections(
    const std::vector<detect::LabeledDetection>& detections,
    const DetectorClassMap& class_map, float min_score, int width, int height) {
  std::vector<ObjectDetection> out;
  for (const detect::LabeledDetection& d : detections) {
    if (d.score < min_score) continue;
    const auto id = class_map.Map(d.class_id);
    if (!id) continue;
    ObjectDetection o;
    o.box = PromptBox(d.box, width, height);
    if (o.box.area() == 0) continue;
    o.class_id = *id;
    o.detector_class = d.class_id;
    o.score = static_cast<float>(d.score);
    out.push_back(o);
  }
  return out;
}

std::vector<Mask> DecodeDetectionMasks(
    const PromptableSegmenter& model,
    const std::vector<ObjectDetection>& detections, int min_region_area_px) {
  std::vector<Mask> masks(detections.size());
  tbb::parallel_for(static_cast<size_t>(0), detections.size(), [&](size_t i) {
    Prompt prompt;
    prompt.box = detections[i].box;
    const LowResMask low = model.Decode(prompt);
    masks[i] = model.Upsample(low);
    masks[i].predicted_iou = low.predicted_iou;
    masks[i].stability = model.StabilityScore(low, 0.0f, 1.0f);
    const Box& b = detections[i].box;
    masks[i].point_x = 0.5f * static_cast<float>(b.x0 + b.x1);
    masks[i].point_y = 0.5f * static_cast<float>(b.y0 + b.y1);
    RemoveSmallRegions(&masks[i], min_region_area_px);
  });
  return masks;
}

ObjectEvidence AttachDetections(std::vector<Mask> masks,
                                const std::vector<ObjectDetection>& detections,
                                std::vector<Mask> detection_masks,
                                const ObjectDetectorOptions& options) {
  CheckArgument(detections.size() == detection_masks.size(),
                "object evidence: one mask per detection expected");
  const size_t generated = masks.size();
  std::vector<MaskEvidence> evidence(generated);
  // Stuff yields only in masks shaped like the object (matched or added):
  // a part may be the road under a car that its box-prompted mask took in.
  const auto add = [&](MaskEvidence* e, uint16_t cls, float strength,
                       bool whole) {
    e->weights.push_back({cls, options.weight * strength});
    if (options.stuff_yields && whole) {
      e->stuff_scale = std::min(e->stuff_scale, 1.0f - strength);
    }
  };
  std::vector<int> source(generated, -1);
  // Per generated mask: (share inside, detection) of the best holder.
  std::vector<std::pair<double, int>> holder(generated, {0.0, -1});
  ObjectEvidence result;
  for (size_t d = 0; d < detections.size(); ++d) {
    const Mask& dm = detection_masks[d];
    if (dm.area == 0) continue;
    const float score = detections[d].score;
    const uint16_t cls = detections[d].class_id;
    int best = -1;
    double best_iou = 0;
    std::vector<std::pair<size_t, double>> parts;
    for (size_t m = 0; m < generated; ++m) {
      if (BoxIoU(masks[m].box, dm.box) == 0) continue;
      const int64_t inter = MaskIntersection(masks[m], dm);
      if (inter == 0) continue;
      const double iou = static_cast<double>(inter) /
                         static_cast<double>(masks[m].area + dm.area - inter);
      if (iou >= options.match_iou && iou > best_iou) {
        best = static_cast<int>(m);
        best_iou = iou;
      }
      const double inside =
          static_cast<double>(inter) / static_cast<double>(masks[m].area);
      if (options.part_containment > 0 && masks[m].area < dm.area &&
          inside >= options.part_containment) {
        parts.emplace_back(m, inside);
      }
    }
    if (best >= 0) {
      add(&evidence[best], cls, score, true);
      source[best] = static_cast<int>(d);
      ++result.matched;
    } else if (dm.predicted_iou >= options.min_predicted_iou) {
      masks.push_back(dm);
      evidence.emplace_back();
      add(&evidence.back(), cls, score, true);
      source.push_back(static_cast<int>(d));
      ++result.added;
    }
    for (const auto& [m, inside] : parts) {
      if (static_cast<int>(m) == best) continue;
      add(&evidence[m], cls, static_cast<float>(score * inside), false);
      if (inside > holder[m].first) holder[m] = {inside, static_cast<int>(d)};
      ++result.parts;
    }
  }
  // Large to small, as the vote paints them.
  std::vector<size_t> order(masks.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return masks[a].area > masks[b].area;
  });
  for (size_t i : order) {
    result.masks.push_back(std::move(masks[i]));
    result.evidence.push_back(std::move(evidence[i]));
    result.detection.push_back(source[i]);
    result.part_of.push_back(i < generated ? holder[i].second : -1);
  }
  return result;
}

std::vector<uint16_t> JoinDetectedParts(
    const std::vector<ObjectDetection>& detections,
    const std::vector<int>& mask_detection, const std::vector<int>& part_of,
    VoteResult* vote, int* joined) {
  CheckArgument(vote != nullptr, "JoinDetectedParts: vote is null");
  const size_t n = vote->mask_labels.size();
  CheckArgument(mask_detection.size() == n && part_of.size() == n,
                "JoinDetectedParts: one detection and holder per mask");
  // Masks are largest first: the first member of a group keeps its id.
  UnionFind groups(n);
  std::vector<int> first(detections.size(), -1);
  for (size_t m = 0; m < n; ++m) {
    for (const int d : {mask_detection[m], part_of[m]}) {
      if (d < 0 || static_cast<size_t>(d) >= detections.size() ||
          vote->mask_labels[m] != detections[static_cast<size_t>(d)].class_id) {
        continue;
      }
      int& f = first[static_cast<size_t>(d)];
      if (f < 0) {
        f = static_cast<int>(m);
      } else {
        groups.Unite(static_cast<size_t>(f), m);
      }
    }
  }
  std::vector<uint16_t> instance(n);
  std::vector<size_t> smallest(n, n);
  for (size_t m = 0; m < n; ++m) {
    size_t& s = smallest[groups.Find(m)];
    s = std::min(s, m);
  }
  int count = 0;
  std::vector<uint16_t> remap(n + 1);
  for (size_t m = 0; m < n; ++m) {
    instance[m] = static_cast<uint16_t>(smallest[groups.Find(m)] + 1);
    remap[m + 1] = instance[m];
    count += instance[m] != m + 1;
  }
  if (count > 0) {
    uint16_t* ids = vote->instance.data();
    for (size_t i = 0; i < vote->instance.NumPixels(); ++i) {
      if (ids[i] >= 1 && ids[i] <= n) ids[i] = remap[ids[i]];
    }
  }
  if (joined != nullptr) *joined = count;
  return instance;
}

}  // namespace semrec::segment
