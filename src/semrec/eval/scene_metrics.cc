#include "semrec/eval/scene_metrics.h"

#include <algorithm>
#include <limits>
#include <map>
#include <numeric>

#include <tbb/parallel_for.h>

#include <fmt/format.h>

#include "semrec/core/error.h"
#include "semrec/eval/c2c.h"
#include "semrec/io/ply_io.h"

namespace semrec::eval {
namespace {

// Instance bookkeeping of one class at one IoU threshold (ScanNet's
// evaluate_matches): returns the (true positive, score) list and the number of
// ground-truth objects left unmatched.
struct ClassMatches {
  std::vector<bool> true_positive;
  std::vector<double> score;
  size_t hard_false_negatives = 0;
  size_t matched_gt = 0;
  size_t matched_predictions = 0;
};

struct Overlaps {
  // Sizes in ground-truth points.
  std::map<int32_t, size_t> gt_size;  // gt object -> points
  std::vector<size_t> pred_size;      // prediction -> points
  std::map<std::pair<size_t, int32_t>, size_t> intersection;  // (pred, gt)
  double Iou(size_t pred, int32_t gt) const {
    const auto it = intersection.find({pred, gt});
    if (it == intersection.end()) return 0.0;
    const double inter = static_cast<double>(it->second);
    return inter / (static_cast<double>(pred_size[pred]) +
                    static_cast<double>(gt_size.at(gt)) - inter);
  }
};

ClassMatches MatchClass(const std::vector<int32_t>& gt_objects,
                        const std::vector<size_t>& predictions,
                        const std::vector<PredictedObject>& predicted,
                        const Overlaps& overlaps, double threshold) {
  ClassMatches m;
  // Highest confidence first, so the first match of a ground-truth object is
  // its best-scored prediction (ScanNet keeps the max score either way).
  std::vector<size_t> order = predictions;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return predicted[a].score > predicted[b].score;
  });
  std::vector<double> gt_score(gt_objects.size(),
                               -std::numeric_limits<double>::infinity());
  std::vector<bool> gt_matched(gt_objects.size(), false);
  std::vector<bool> visited(predicted.size(), false);
  std::vector<bool> extra_true;
  std::vector<double> extra_score;
  for (size_t g = 0; g < gt_objects.size(); ++g) {
    bool found = false;
    for (size_t p : order) {
      if (visited[p] || overlaps.Iou(p, gt_objects[g]) <= threshold) continue;
      const double confidence = predicted[p].score;
      if (found) {  // a duplicate: a false positive at the lower score
        extra_true.push_back(false);
        extra_score.push_back(std::min(gt_score[g], confidence));
        gt_score[g] = std::max(gt_score[g], confidence);
      } else {
        found = true;
        gt_matched[g] = true;
        gt_score[g] = confidence;
        visited[p] = true;
      }
    }
    if (!found) ++m.hard_false_negatives;
  }
  for (size_t g = 0; g < gt_objects.size(); ++g) {
    if (!gt_matched[g]) continue;
    m.true_positive.push_back(true);
    m.score.push_back(gt_score[g]);
    ++m.matched_gt;
  }
  m.true_positive.insert(m.true_positive.end(), extra_true.begin(),
                         extra_true.end());
  m.score.insert(m.score.end(), extra_score.begin(), extra_score.end());
  // Predictions that match no ground-truth object of their class.
  for (size_t p : order) {
    const bool matches =
        std::any_of(gt_objects.begin(), gt_objects.end(),
                    [&](int32_t g) { return overlaps.Iou(p, g) > threshold; });
    if (matches) {
      ++m.matched_predictions;
    } else {
      m.true_positive.push_back(false);
      m.score.push_back(predicted[p].score);
    }
  }
  return m;
}

}  // namespace

void SceneEvalOptions::Check() const {
  CheckArgument(radius_m > 0.0, "eval scene: radius_m must be > 0");
}

SceneGroundTruth ReadSceneGroundTruth(const std::filesystem::path& path) {
  io::PlyData ply = io::ReadPly(path);
  SceneGroundTruth gt;
  for (auto& [name, values] : ply.int_properties) {
    if (name == "semantic") gt.semantic = std::move(values);
    if (name == "instance") gt.instance = std::move(values);
  }
  if (gt.semantic.empty() || gt.instance.empty()) {
    throw FormatError(path,
                      "a scene ground truth needs per-point 'semantic' and "
                      "'instance' properties (semrec synth writes them in "
                      "gt/surface_points.ply)");
  }
  if (ply.points.empty()) throw FormatError(path, "has no points");
  gt.points = std::move(ply.points);
  return gt;
}

std::vector<uint16_t> ObservedViews(const std::vector<Eigen::Vector3f>& points,
                                    const io::SequenceReader& reader,
                                    double tolerance_m,
                                    const ProgressOptions& progress_options) {
  Progress progress("checking what the frames saw", reader.size(),
                    progress_options);
  std::vector<uint16_t> views(points.size(), 0);
  for (size_t f = 0; f < reader.size(); ++f) {
    const Frame frame = reader.Read(f);
    const Transform T_camera_world = frame.T_world_camera.Inverse();
    const CameraIntrinsics& k = frame.intrinsics;
    tbb::parallel_for(size_t{0}, points.size(), [&](size_t i) {
      const Eigen::Vector3d p = T_camera_world * points[i].cast<double>();
      if (p.z() <= 0.0) return;
      const Eigen::Vector2d uv = k.Project(p);
      const int64_t u = std::lround(uv.x()), v = std::lround(uv.y());
      if (u < 0 || v < 0 || u >= frame.depth.width() ||
          v >= frame.depth.height()) {
        return;
      }
      const float z = frame.depth(static_cast<int>(u), static_cast<int>(v));
      if (z > 0.0f && std::abs(z - p.z()) <= tolerance_m &&
          views[i] < std::numeric_limits<uint16_t>::max()) {
        ++views[i];
      }
    });
    progress.Tick();
  }
  return views;
}

SceneGroundTruth Subset(const SceneGroundTruth& gt,
                        const std::vector<bool>& keep) {
  CheckArgument(keep.size() == gt.points.size(),
                "eval scene: one flag per ground-truth point");
  SceneGroundTruth out;
  for (size_t i = 0; i < keep.size(); ++i) {
    if (!keep[i]) continue;
    out.points.push_back(gt.points[i]);
    out.semantic.push_back(gt.semantic[i]);
    out.instance.push_back(gt.instance[i]);
    if (!gt.views.empty()) out.views.push_back(gt.views[i]);
  }
  return out;
}

double ScanNetAveragePrecision(const std::vector<bool>& true_positive,
                               const std::vector<double>& score,
                               size_t hard_false_negatives) {
  CheckArgument(true_positive.size() == score.size(),
                "average precision: one score per prediction");
  const size_t n = score.size();
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return score[a] < score[b]; });
  std::vector<double> cumsum(n);
  std::vector<size_t> unique_first;  // first index of each distinct score
  double running = 0.0;
  for (size_t i = 0; i < n; ++i) {
    running += true_positive[order[i]] ? 1.0 : 0.0;
    cumsum[i] = running;
    if (i == 0 || score[order[i]] != score[order[i - 1]]) {
      unique_first.push_back(i);
    }
  }
  const double num_true = n > 0 ? cumsum.back() : 0.0;
  std::vector<double> precision(unique_first.size() + 1),
      recall(unique_first.size() + 1);
  for (size_t k = 0; k < unique_first.size(); ++k) {
    const size_t idx = unique_first[k];
    const double before = idx > 0 ? cumsum[idx - 1] : 0.0;
    const double tp = num_true - before;
    const double fp = static_cast<double>(n - idx) - tp;
    const double fn = before + static_cast<double>(hard_false_negatives);
    precision[k] = tp + fp > 0 ? tp / (tp + fp) : 0.0;
    recall[k] = tp + fn > 0 ? tp / (tp + fn) : 0.0;
  }
  precision.back() = 1.0;
  recall.back() = 0.0;
  // Step widths: 0.5 * (r[i-1] - r[i+1]) with r[-1] = r[0] and a trailing 0.
  std::vector<double> r;
  r.push_back(recall.front());
  r.insert(r.end(), recall.begin(), recall.end());
  r.push_back(0.0);
  double ap = 0.0;
  for (size_t i = 0; i < precision.size(); ++i) {
    ap += precision[i] * 0.5 * (r[i] - r[i + 2]);
  }
  return ap;
}

GtObjectReport ReportObject(int32_t gt_id, int32_t class_id,
                            const std::vector<PredictedObject>& predicted,
                            const Overlaps& overlaps) {
  GtObjectReport r;
  r.id = gt_id;
  r.class_id = class_id;
  r.points = overlaps.gt_size.at(gt_id);
  if (r.points == 0) return r;
  const auto total = static_cast<double>(r.points);
  size_t covered = 0;
  for (size_t p = 0; p < predicted.size(); ++p) {
    const auto it = overlaps.intersection.find({p, gt_id});
    if (it == overlaps.intersection.end()) continue;
    covered += it->second;
    if (predicted[p].class_id == class_id) {
      r.best_iou = std::max(r.best_iou, overlaps.Iou(p, gt_id));
    }
    const double share = static_cast<double>(it->second) / total;
    if (share >= 0.05) {
      r.shares.push_back({predicted[p].id, predicted[p].class_id, share});
    }
  }
  std::sort(r.shares.begin(), r.shares.end(),
            [](const auto& a, const auto& b) { return a.share > b.share; });
  // Points of this object that took no predicted object at all. Those that
  // took one are counted in `covered` (also below the 5% listing floor).
  r.uncovered = 1.0 - static_cast<double>(covered) / total;
  return r;
}

namespace {

constexpr size_t kNone = std::numeric_limits<size_t>::max();

// Label transfer: each ground-truth point takes its nearest predicted surface
// point's object, within the radius (kNone: none).
std::vector<size_t> TransferLabels(
    const SceneGroundTruth& gt, const std::vector<PredictedObject>& predicted,
    double radius_m) {
  std::vector<Eigen::Vector3f> surface;
  std::vector<size_t> owner;
  for (size_t p = 0; p < predicted.size(); ++p) {
    surface.insert(surface.end(), predicted[p].surface.begin(),
                   predicted[p].surface.end());
    owner.insert(owner.end(), predicted[p].surface.size(), p);
  }
  std::vector<size_t> assigned(gt.points.size(), kNone);
  if (surface.empty()) return assigned;
  const auto nearest = NearestNeighbors(gt.points, surface);
  for (size_t i = 0; i < gt.points.size(); ++i) {
    if (nearest[i].second <= radius_m) assigned[i] = owner[nearest[i].first];
  }
  return assigned;
}

// Semantic IoU per ground-truth class (into *per_class, their mean into m),
// and the instance overlaps the AP matching needs.
Overlaps SemanticIou(const SceneGroundTruth& gt,
                     const std::vector<PredictedObject>& predicted,
                     const std::vector<size_t>& assigned,
                     std::map<int32_t, SceneClassMetrics>* per_class,
                     SceneMetrics* m) {
  const size_t n = gt.points.size();
  for (size_t i = 0; i < n; ++i) {
    if (gt.semantic[i] < 0) continue;  // ignored ground truth
    (*per_class)[gt.semantic[i]].id = gt.semantic[i];
  }
  Overlaps overlaps;
  overlaps.pred_size.assign(predicted.size(), 0);
  for (size_t i = 0; i < n; ++i) {
    const int32_t truth = gt.semantic[i];
    if (truth < 0) continue;
    m->covered_points += assigned[i] != kNone;
    const int32_t pred =
        assigned[i] != kNone ? predicted[assigned[i]].class_id : -1;
    if (pred == truth) {
      ++(*per_class)[truth].true_positives;
    } else {
      ++(*per_class)[truth].false_negatives;
      if (const auto it = per_class->find(pred); it != per_class->end()) {
        ++it->second.false_positives;
      }
    }
    if (gt.instance[i] > 0) ++overlaps.gt_size[gt.instance[i]];
    if (assigned[i] != kNone) {
      ++overlaps.pred_size[assigned[i]];
      if (gt.instance[i] > 0) {
        ++overlaps.intersection[{assigned[i], gt.instance[i]}];
      }
    }
  }
  double iou_sum = 0.0;
  for (auto& [id, c] : *per_class) {
    const double denom = static_cast<double>(
        c.true_positives + c.false_positives + c.false_negatives);
    c.iou = denom > 0 ? static_cast<double>(c.true_positives) / denom : 0.0;
    iou_sum += c.iou;
  }
  m->mean_iou = per_class->empty()
                    ? 0.0
                    : iou_sum / static_cast<double>(per_class->size());
  return overlaps;
}

// Ground-truth objects of the thing classes, by class: an object's class is
// its points' majority.
std::map<int32_t, std::vector<int32_t>> GtObjectsOfClass(
    const SceneGroundTruth& gt, const std::set<int32_t>& thing_classes) {
  std::map<int32_t, std::map<int32_t, size_t>> object_votes;
  for (size_t i = 0; i < gt.points.size(); ++i) {
    if (gt.instance[i] > 0 && gt.semantic[i] >= 0) {
      ++object_votes[gt.instance[i]][gt.semantic[i]];
    }
  }
  std::map<int32_t, std::vector<int32_t>> out;
  for (const auto& [object, votes] : object_votes) {
    const auto best = std::max_element(
        votes.begin(), votes.end(),
        [](const auto& a, const auto& b) { return a.second < b.second; });
    if (thing_classes.count(best->first) != 0) {
      out[best->first].push_back(object);
    }
  }
  return out;
}

// Per ground-truth object of a class: the predicted pieces holding >= 10% of
// it, and its report line.
void ReportObjects(const std::vector<int32_t>& objects, int32_t cls,
                   const std::vector<PredictedObject>& predicted,
                   const Overlaps& overlaps,
                   const std::map<int32_t, uint16_t>& views_of,
                   SceneMetrics* m) {
  for (int32_t g : objects) {
    size_t pieces = 0;
    for (size_t p = 0; p < predicted.size(); ++p) {
      const auto it = overlaps.intersection.find({p, g});
      if (it != overlaps.intersection.end() &&
          10 * it->second >= overlaps.gt_size.at(g)) {
        ++pieces;
      }
    }
    m->pieces_per_gt_object[g] = pieces;
    m->objects.push_back(ReportObject(g, cls, predicted, overlaps));
    if (const auto it = views_of.find(g); it != views_of.end()) {
      m->objects.back().views = it->second;
    }
  }
}

// ScanNet-style AP25/AP50 per thing class and their means, recall and
// precision at IoU 0.5, the objects' report.
void InstanceMetrics(const SceneGroundTruth& gt,
                     const std::vector<PredictedObject>& predicted,
                     const std::set<int32_t>& thing_classes,
                     const Overlaps& overlaps,
                     std::map<int32_t, SceneClassMetrics>* per_class,
                     SceneMetrics* m) {
  const auto gt_objects_of_class = GtObjectsOfClass(gt, thing_classes);
  std::map<int32_t, std::vector<size_t>> predictions_of_class;
  for (size_t p = 0; p < predicted.size(); ++p) {
    if (thing_classes.count(predicted[p].class_id) != 0) {
      predictions_of_class[predicted[p].class_id].push_back(p);
      ++m->predicted_objects;
    }
  }
  double ap25_sum = 0.0, ap50_sum = 0.0;
  size_t classes_with_objects = 0, matched_gt50 = 0, matched_pred50 = 0;
  // Per object, the most frames that saw one of its points.
  std::map<int32_t, uint16_t> views_of;
  for (size_t i = 0; i < gt.views.size(); ++i) {
    uint16_t& v = views_of[gt.instance[i]];
    v = std::max(v, gt.views[i]);
  }
  for (const auto& [cls, objects] : gt_objects_of_class) {
    const auto& preds = predictions_of_class[cls];
    const ClassMatches m25 =
        MatchClass(objects, preds, predicted, overlaps, 0.25);
    const ClassMatches m50 =
        MatchClass(objects, preds, predicted, overlaps, 0.5);
    SceneClassMetrics& c = (*per_class)[cls];
    c.id = cls;
    c.has_instances = true;
    c.gt_objects = objects.size();
    c.ap25 = ScanNetAveragePrecision(m25.true_positive, m25.score,
                                     m25.hard_false_negatives);
    c.ap50 = ScanNetAveragePrecision(m50.true_positive, m50.score,
                                     m50.hard_false_negatives);
    ap25_sum += c.ap25;
    ap50_sum += c.ap50;
    ++classes_with_objects;
    m->gt_objects += objects.size();
    matched_gt50 += m50.matched_gt;
    matched_pred50 += m50.matched_predictions;
    ReportObjects(objects, cls, predicted, overlaps, views_of, m);
  }
  std::sort(m->objects.begin(), m->objects.end(),
            [](const auto& a, const auto& b) { return a.id < b.id; });
  if (classes_with_objects > 0) {
    m->ap25 = ap25_sum / static_cast<double>(classes_with_objects);
    m->ap50 = ap50_sum / static_cast<double>(classes_with_objects);
  }
  if (m->gt_objects > 0) {
    m->recall50 =
        static_cast<double>(matched_gt50) / static_cast<double>(m->gt_objects);
    m->objects_per_gt_object = static_cast<double>(m->predicted_objects) /
                               static_cast<double>(m->gt_objects);
  }
  if (m->predicted_objects > 0) {
    m->precision50 = static_cast<double>(matched_pred50) /
                     static_cast<double>(m->predicted_objects);
  }
}

}  // namespace

SceneMetrics EvaluateScene(const SceneGroundTruth& gt,
                           const std::vector<PredictedObject>& predicted,
                           const std::set<int32_t>& thing_classes,
                           const SceneEvalOptions& options) {
  options.Check();
  const size_t n = gt.points.size();
  CheckArgument(gt.semantic.size() == n && gt.instance.size() == n,
                "eval scene: one class and instance per ground-truth point");
  CheckArgument(gt.views.empty() || gt.views.size() == n,
                "eval scene: views for every ground-truth point or none");
  SceneMetrics m;
  m.gt_points = n;
  const std::vector<size_t> assigned =
      TransferLabels(gt, predicted, options.radius_m);
  std::map<int32_t, SceneClassMetrics> per_class;
  const Overlaps overlaps =
      SemanticIou(gt, predicted, assigned, &per_class, &m);
  InstanceMetrics(gt, predicted, thing_classes, overlaps, &per_class, &m);
  for (auto& [id, c] : per_class) m.classes.push_back(c);
  return m;
}

}  // namespace semrec::eval
