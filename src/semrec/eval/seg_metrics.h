// Semantic segmentation metrics: mIoU / mAcc / pAcc with ADE20K's conventions,
// and boundary quality (Boundary IoU, Cheng et al. 2021; boundary F-score).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <vector>

#include "semrec/core/label_map.h"

namespace semrec::eval {

struct SegEvalOptions {
  /// ADE20K: ground-truth 0 = unlabelled, ignored (predictions there too).
  bool ignore_zero = true;
  /// Ground-truth value ignored as well (-1 = none).
  int ignore_label = 255;
  /// Boundary IoU band width d = round(ratio * image diagonal), >= 1 (the
  /// paper's default 0.02).
  double boundary_dilation_ratio = 0.02;
  /// Boundary F-score: a boundary pixel matches when the other boundary is
  /// within this many pixels.
  int boundary_tolerance_px = 2;
  void Check() const;
};

struct ClassSegMetrics {
  uint16_t id = 0;
  int64_t intersection = 0;  // pixels labelled id in both
  int64_t gt_pixels = 0;
  int64_t pred_pixels = 0;  // over non-ignored ground-truth pixels
  double iou = 0, accuracy = 0;
  int64_t boundary_intersection = 0, boundary_union = 0;
  double boundary_iou = 0;
  double boundary_precision = 0, boundary_recall = 0, boundary_f = 0;
};

struct SegMetrics {
  /// Per class with gt_pixels + pred_pixels > 0, by id.
  std::vector<ClassSegMetrics> classes;
  /// Correct / valid pixels over all images.
  double pixel_accuracy = 0;
  /// Means over the classes present (union > 0 for IoUs, gt > 0 for mAcc,
  /// boundary pixels present for F): absent classes are left out, as
  /// mmsegmentation's nanmean does. ADE20K's own script averages over all 150
  /// classes, which only equals this when every class occurs (the full
  /// validation set); on subsets it would count absent classes as 0.
  double mean_iou = 0;
  double mean_accuracy = 0;
  double mean_boundary_iou = 0;
  double mean_boundary_f = 0;
  int64_t valid_pixels = 0;
  int images = 0;
};

/// Accumulates over images (a dataset's metrics are ratios of sums, not means
/// of per-image values).
class SegEvaluator {
 public:
  explicit SegEvaluator(const SegEvalOptions& options = {});
  /// Throws InvalidArgument when the sizes differ.
  void Add(const LabelMap& prediction, const LabelMap& ground_truth);
  SegMetrics Result() const;

 private:
  struct Counts {
    int64_t intersection = 0, gt = 0, pred = 0;
    int64_t b_inter = 0, b_union = 0;
    int64_t pred_b = 0, pred_b_matched = 0, gt_b = 0, gt_b_matched = 0;
  };
  SegEvalOptions options_;
  std::map<uint16_t, Counts> counts_;
  int64_t correct_ = 0, valid_ = 0;
  int images_ = 0;
};

/// The Boundary IoU band of a 0/1 mask as in the reference implementation:
/// pad one pixel of 0, erode `d` times with a 3x3 kernel, subtract (so the
/// image border counts as a contour).
Image<uint8_t> BoundaryBand(const Image<uint8_t>& mask, int d);

/// Pairs of files for `semrec eval seg`: every PNG of `gt_dir` with the
/// prediction of the same stem in `pred_dir` (also accepted: <stem>_semantic
/// .png, or pred_dir/semantic/<stem>.png as `semrec segment` writes). Throws
/// IoError naming the missing prediction.
std::vector<std::pair<std::filesystem::path, std::filesystem::path>>
MatchSegFiles(const std::filesystem::path& pred_dir,
              const std::filesystem::path& gt_dir);

}  // namespace semrec::eval
