// `semrec eval scene|mot|seg` as library calls on files: a written result
// (`semrec run` / `semrec mesh` output, or its scene.usda) against a labelled
// ground-truth cloud, in the result's upright frame, with the class map and
// the observed-points filter; MOTChallenge files; label PNG folders. The CLI
// prints them, the Python module returns them as dicts (the JSON here).
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>

#include <nlohmann/json.hpp>

#include "semrec/core/label_map.h"
#include "semrec/core/transform.h"
#include "semrec/eval/c2c.h"
#include "semrec/eval/mot.h"
#include "semrec/eval/scene_metrics.h"
#include "semrec/eval/seg_metrics.h"

namespace semrec::eval {

struct SceneResultOptions {
  /// A result folder (its scene.usda) or a .usda file.
  std::filesystem::path result;
  /// Ground-truth PLY with per-point `semantic` and `instance`.
  std::filesystem::path gt;
  /// Ground-truth label set; empty = classes.json beside `gt`.
  std::filesystem::path gt_classes;
  /// Predicted class name -> ground-truth name or id (JSON); empty = by name.
  std::filesystem::path class_map;
  /// Score only ground-truth points some frame of this sequence saw (empty =
  /// all), every `observed_stride`-th frame.
  std::filesystem::path observed_in;
  int observed_stride = 1;
  /// A result built from estimated poses (its folder holds poses.txt) lies
  /// in the first camera's frame: its poses are aligned to this trajectory
  /// (eval::ReadTrajectory: the recording, or a TUM file) and the ground
  /// truth is moved into the result's frame. Required for such a result.
  std::filesystem::path gt_trajectory;
  io::SequenceReaderOptions gt_trajectory_options;
  SceneEvalOptions metrics;
  /// Throws InvalidArgument for a missing result/ground truth path or a bad
  /// stride.
  void Check() const;
};

struct SceneResultEvaluation {
  SceneMetrics metrics;
  LabelSet gt_classes;
  /// The scene file scored.
  std::filesystem::path scene;
  /// Ground-truth points before the observed-points filter.
  size_t all_points = 0;
  /// Predicted class names that map to no ground-truth class, with counts.
  std::map<std::string, size_t> unmapped;
  /// A ground-truth class id's name ("(id)" when unknown).
  std::string ClassName(int32_t id) const;
  /// Everything above as `semrec eval scene --json` prints it.
  nlohmann::json ToJson() const;
  /// The summary `semrec eval scene` prints: the scores, per class, and with
  /// `per_object` where each ground-truth object's points went.
  std::string Text(const SceneResultOptions& options, bool per_object) const;
};

/// Scores `options.result`. Throws IoError/FormatError naming the file for
/// unreadable inputs, and FormatError when the result was turned upright but
/// says nowhere by which transform.
/// A written result's surface (every prim's mesh vertices) in the world
/// frame of the recording's poses: its upright transform undone and, for a
/// result built from estimated poses (poses.txt), the alignment to
/// `gt_trajectory` applied (required then, as for EvaluateSceneResult).
std::vector<Eigen::Vector3f> ResultSurfaceInWorld(
    const std::filesystem::path& result,
    const std::filesystem::path& gt_trajectory = {},
    const io::SequenceReaderOptions& gt_trajectory_options = {});

SceneResultEvaluation EvaluateSceneResult(const SceneResultOptions& options);

/// The transform that turned a result upright (T_upright_world): from its
/// layers' customLayerData; identity only when they do not say it was turned.
Transform ResultUprightTransform(const std::filesystem::path& scene);

/// Predicted class name -> ground-truth id from a class-map JSON (see
/// data/class_maps/); -1 for names mapped to null.
std::map<std::string, int32_t> LoadClassMap(const std::filesystem::path& path,
                                            const LabelSet& gt_classes);

/// MOT metrics as `semrec eval mot --json` prints them.
nlohmann::json MotMetricsJson(const MotMetrics& m);
/// ... and as its summary (`result` against `gt`, the files' names).
std::string MotMetricsText(const MotMetrics& m, const std::string& result,
                           const std::string& gt);

/// C2C distances as `semrec eval c2c --json` prints them (mm), and as its
/// summary (`estimate` against `reference` of `reference_points`).
nlohmann::json DistanceStatsJson(const DistanceStats& s);
std::string DistanceStatsText(const DistanceStats& s,
                              const std::string& estimate,
                              const std::string& reference,
                              size_t reference_points);

/// MOTChallenge ground truth vs a tracker's output (files).
MotMetrics EvaluateMotFiles(const std::filesystem::path& gt,
                            const std::filesystem::path& result);

/// Label PNGs matched by name (MatchSegFiles) with ground-truth classes the
/// set does not name folded into its catch-all class. FormatError naming the
/// file for a prediction of another size than its ground truth.
SegMetrics EvaluateSegFolders(const std::filesystem::path& pred,
                              const std::filesystem::path& gt,
                              const LabelSet& labels,
                              const SegEvalOptions& options);

/// Segmentation metrics as `semrec eval seg --json` prints them, and as its
/// summary with a per-class table.
nlohmann::json SegMetricsJson(const SegMetrics& m, const LabelSet& labels);
std::string SegMetricsText(const SegMetrics& m, const LabelSet& labels,
                           int boundary_tolerance_px);

}  // namespace semrec::eval
