// Semantic segmentation metrics: mIoU / mAcc / pAcc with ADE20K's conventions,
// and boundary quality (Boundary IoU, Cheng et al. 2021; boundary F-score).
//
// Region metrics follow the ADE20K scene-parsing evaluation
// (`intersectionAndUnion` / `pixelAccuracy` of CSAILVision/sceneparsing):
// ground-truth 0 is unlabelled and the prediction there is not scored; a
// predicted 0 on a labelled pixel is wrong and is not a class. Ground-truth
// `ignore_label` (255) is treated like 0. Differences from that script:
//  - means are over the classes that occur (ground-truth or predicted pixels;
//    mmsegmentation's nanmean). The ADE20K script averages over all 150
//    classes, which is the same on the full validation set but counts absent
//    classes as 0 on a subset.
//  - any other predicted value is a class of its own (the script's histogram
//    drops values above 150); a prediction outside the label set thus costs
//    IoU instead of being silently lost.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <utility>
#include <vector>

#include "semrec/core/label_map.h"

namespace semrec::eval {

struct SegEvalOptions {
  /// Ground-truth 0 = unlabelled, ignored (ADE20K). Off: 0 is a class (VOC
  /// background).
  bool ignore_zero = true;
  /// Ground-truth value ignored as well; -1 = none.
  int ignore_label = 255;
  /// Boundary IoU band width d = round(ratio * image diagonal), at least 1
  /// (the paper's 0.02).
  double boundary_dilation_ratio = 0.02;
  /// Boundary F-score: a contour pixel matches when the other mask's contour
  /// is within this Euclidean distance (pixels).
  int boundary_tolerance_px = 2;
  /// Throws InvalidArgument for a ratio outside (0, 1), a negative tolerance
  /// or an ignore label outside -1..65535.
  void Check() const;
};

/// Ground-truth ids the label set cannot name become its catch-all class
/// (kind "other") when it has one at id 0: scoring ADE20K-150 ground truth
/// against a top-31 model counts a chair as a chair and a lamp as "other"
/// (0, ignored with ignore_zero). Returns the number of pixels changed; does
/// nothing for a set without such a class.
size_t FoldUnnamedIntoCatchAll(const LabelSet& labels, LabelMap* gt);

/// Metrics of one class, from counts summed over all images.
struct ClassSegMetrics {
  uint16_t id = 0;
  int64_t intersection = 0;  // Labelled id in both.
  int64_t union_pixels = 0;  // Labelled id in either.
  int64_t gt_pixels = 0;
  int64_t pred_pixels = 0;  // Predicted id on scored (labelled) pixels.
  double iou = 0;
  double accuracy = 0;  // intersection / gt_pixels; 0 without gt pixels.
  int64_t boundary_intersection = 0, boundary_union = 0;
  double boundary_iou = 0;
  double boundary_precision = 0, boundary_recall = 0, boundary_f = 0;
};

struct SegMetrics {
  /// Classes with ground-truth or predicted pixels, by id.
  std::vector<ClassSegMetrics> classes;
  /// Correct / scored pixels over all images.
  double pixel_accuracy = 0;
  /// Means over `classes` (mAcc over those with ground-truth pixels).
  double mean_iou = 0;
  double mean_accuracy = 0;
  double mean_boundary_iou = 0;
  double mean_boundary_f = 0;
  int64_t valid_pixels = 0;  // Scored (labelled, not ignored) pixels.
  int images = 0;
};

/// Boundary IoU's band width for an image: round(ratio * diagonal), >= 1.
int BoundaryBandWidth(double dilation_ratio, int width, int height);

/// Accumulates over images: dataset metrics are ratios of summed counts, not
/// means of per-image values.
///
/// Boundaries are computed per class on binary masks restricted to scored
/// pixels (an unlabelled region cuts both masks alike):
///  - Boundary IoU: band = mask minus its erosion by a (2d+1)^2 square, with
///    pixels outside the image counting as outside the mask, as the
///    reference implementation's zero padding does (a mask cut by the image
///    border has a contour there). Per class |G_d & P_d| / |G_d | P_d|, both
///    summed over images.
///  - Boundary F: contours are the d = 1 bands (same border convention);
///    precision = predicted contour pixels within the tolerance of a
///    ground-truth contour pixel / predicted contour pixels, recall the other
///    way round, F = 2PR / (P + R), counts summed over images. A class with
///    only one side present has F = 0.
/// Each image costs one pass over the pixels plus, per class present, work on
/// the class's bounding box only.
class SegEvaluator {
 public:
  /// Throws InvalidArgument when the options are invalid.
  explicit SegEvaluator(const SegEvalOptions& options = {});
  /// Throws InvalidArgument when the sizes differ.
  void Add(const LabelMap& prediction, const LabelMap& ground_truth);
  SegMetrics Result() const;

 private:
  struct Counts {
    int64_t intersection = 0, gt = 0, pred = 0;
    int64_t band_intersection = 0, band_union = 0;
    int64_t pred_contour = 0, pred_contour_matched = 0;
    int64_t gt_contour = 0, gt_contour_matched = 0;
  };
  bool IsClass(uint16_t label) const;

  SegEvalOptions options_;
  std::map<uint16_t, Counts> counts_;
  int64_t correct_ = 0, valid_ = 0;
  int images_ = 0;
};

/// The Boundary IoU band of a 0/1 mask (1 = band), as above; `d` >= 1.
Image<uint8_t> BoundaryBand(const Image<uint8_t>& mask, int d);

/// Pairs (prediction, ground truth) for `semrec eval seg`: every PNG of
/// `gt_dir`, sorted, with the prediction of the same stem in `pred_dir`
/// (<stem>.png, <stem>_semantic.png, or semantic/<stem>.png as `semrec
/// segment` writes). Throws IoError naming the missing prediction, or with
/// `allow_missing` skips it (IoError when nothing matches at all).
std::vector<std::pair<std::filesystem::path, std::filesystem::path>>
MatchSegFiles(const std::filesystem::path& pred_dir,
              const std::filesystem::path& gt_dir, bool allow_missing = false);

}  // namespace semrec::eval
