// 3D semantic and instance quality of a reconstructed scene, ScanNet-style.
//
// Ground truth is a point cloud with a class (`semantic`) and an object
// (`instance`, 0 = none) per point. Each ground-truth point takes the class
// and object of the nearest predicted surface point within `radius_m`
// (unlabelled otherwise), so both are scored on the same points:
//  - semantic: per ground-truth class IoU = TP / (TP + FP + FN) over the
//    ground-truth points, mIoU over the classes present in the ground truth;
//  - instances (thing classes only): a predicted object is the set of
//    ground-truth points that took it; its IoU with a ground-truth object is
//    computed on those sets; average precision per class at IoU 0.25 and 0.5
//    as ScanNet's benchmark computes it (evaluate_semantic_instance.py:
//    matches by confidence, duplicates are false positives, the
//    precision/recall curve integrated with its step widths), averaged over
//    the classes with ground-truth objects; plus recall and precision at 0.5
//    and the number of predicted objects per ground-truth object.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "semrec/core/progress.h"
#include "semrec/io/sequence_reader.h"

namespace semrec::eval {

struct SceneGroundTruth {
  std::vector<Eigen::Vector3f> points;
  std::vector<int32_t> semantic;
  /// 0 = not an object (structure, unlabelled).
  std::vector<int32_t> instance;
  /// Per point, the frames that saw it (ObservedViews); empty: not known.
  std::vector<uint16_t> views;
};

/// Reads a PLY with per-point `semantic` and `instance` properties. Throws
/// FormatError naming the file when either is missing.
SceneGroundTruth ReadSceneGroundTruth(const std::filesystem::path& path);

struct PredictedObject {
  uint32_t id = 0;
  /// Ground-truth class id it maps to; -1 = none (scored as unlabelled).
  int32_t class_id = -1;
  /// Confidence for the ranking (e.g. fused points or observations).
  double score = 0.0;
  /// Surface samples (mesh vertices), scene frame.
  std::vector<Eigen::Vector3f> surface;
};

struct SceneEvalOptions {
  /// A ground-truth point takes the label of the nearest predicted surface
  /// point within this distance.
  double radius_m = 0.05;
  void Check() const;
};

struct SceneClassMetrics {
  int32_t id = 0;
  int64_t true_positives = 0, false_positives = 0, false_negatives = 0;
  double iou = 0.0;
  /// Instance scores; only for thing classes with ground-truth objects.
  bool has_instances = false;
  size_t gt_objects = 0;
  double ap25 = 0.0, ap50 = 0.0;
};

/// Where one ground-truth object's points went: the predicted objects that
/// took them, largest share first (the rest took no object or another
/// object's share below 5%).
struct GtObjectReport {
  int32_t id = 0;
  int32_t class_id = -1;
  size_t points = 0;
  /// Best IoU with a predicted object of its class (0 = none).
  double best_iou = 0.0;
  struct Share {
    uint32_t predicted_id = 0;
    int32_t class_id = -1;
    double share = 0.0;
  };
  std::vector<Share> shares;
  /// Share of its points near no predicted surface.
  double uncovered = 0.0;
  /// The most frames that saw one of its points (0: not known): 1 = an
  /// object seen in one view.
  uint16_t views = 0;
};

struct SceneMetrics {
  size_t gt_points = 0;
  /// Ground-truth points with a predicted surface within the radius.
  size_t covered_points = 0;
  double mean_iou = 0.0;
  double ap25 = 0.0, ap50 = 0.0;
  /// Ground-truth objects matched at IoU > 0.5 / all; matched predictions /
  /// predictions of mapped thing classes.
  double recall50 = 0.0, precision50 = 0.0;
  size_t gt_objects = 0;
  size_t predicted_objects = 0;
  /// Predicted objects (thing classes) per ground-truth object.
  double objects_per_gt_object = 0.0;
  /// For each ground-truth object, how many predicted objects cover at least
  /// 10% of it (1 = whole; more = in parts).
  std::map<int32_t, size_t> pieces_per_gt_object;
  std::vector<SceneClassMetrics> classes;
  /// One per ground-truth object of a thing class, by id.
  std::vector<GtObjectReport> objects;
};

/// Per ground-truth point, how many frames of `reader` saw it: in the image,
/// in front of the camera, with measured depth within `tolerance_m` of the
/// point's depth (counts stop at 65535). A ground truth sampled from whole
/// objects also holds surfaces no camera saw (backs, undersides), which no
/// reconstruction can recover: `eval scene --observed-in` keeps the points
/// with a count above 0. Reports progress per frame.
std::vector<uint16_t> ObservedViews(const std::vector<Eigen::Vector3f>& points,
                                    const io::SequenceReader& reader,
                                    double tolerance_m = 0.02,
                                    const ProgressOptions& progress = {});

/// The points (and their labels) where `keep` is true.
SceneGroundTruth Subset(const SceneGroundTruth& gt,
                        const std::vector<bool>& keep);

/// `thing_classes`: ground-truth class ids scored as instances.
SceneMetrics EvaluateScene(const SceneGroundTruth& gt,
                           const std::vector<PredictedObject>& predicted,
                           const std::set<int32_t>& thing_classes,
                           const SceneEvalOptions& options = {});

/// ScanNet's average precision from matched flags and scores of the
/// predictions and the number of ground-truth objects left unmatched (hard
/// false negatives). Exposed for tests.
double ScanNetAveragePrecision(const std::vector<bool>& true_positive,
                               const std::vector<double>& score,
                               size_t hard_false_negatives);

}  // namespace semrec::eval
