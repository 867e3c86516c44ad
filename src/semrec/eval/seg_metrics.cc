#include "semrec/eval/seg_metrics.h"

#include <algorithm>
#include <climits>
#include <cmath>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"

namespace fs = std::filesystem;

namespace semrec::eval {

void SegEvalOptions::Check() const {
  CheckArgument(boundary_dilation_ratio > 0 && boundary_dilation_ratio < 1,
                "eval seg: boundary dilation ratio must be in (0, 1)");
  CheckArgument(boundary_tolerance_px >= 0,
                "eval seg: boundary tolerance must be >= 0 pixels");
  CheckArgument(ignore_label >= -1 && ignore_label <= 65535,
                "eval seg: ignore label must be -1..65535");
}

int BoundaryBandWidth(double dilation_ratio, int width, int height) {
  const double diagonal =
      std::hypot(static_cast<double>(width), static_cast<double>(height));
  return std::max(1, static_cast<int>(std::lround(dilation_ratio * diagonal)));
}

namespace {

// Mask pixels within Chebyshev distance `d` of a non-mask pixel, pixels
// outside `mask` counting as non-mask: d iterations of a 3x3 erosion (the
// reference's loop) equal one erosion by a (2d+1)^2 square.
cv::Mat Band(const cv::Mat& mask, int d) {
  cv::Mat eroded;
  cv::erode(
      mask, eroded,
      cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * d + 1, 2 * d + 1)),
      cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
  return mask & ~eroded;
}

// Pixels of `boundary` within Euclidean distance `tolerance` of a pixel of
// `other` (both 0/255 masks of the same size).
int64_t MatchedWithin(const cv::Mat& boundary, const cv::Mat& other,
                      int tolerance) {
  if (cv::countNonZero(other) == 0) return 0;
  cv::Mat dist;
  // distanceTransform measures the distance to the nearest zero pixel.
  cv::distanceTransform(~other, dist, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  // Exact distances are square roots of integers: the slack only absorbs
  // float rounding.
  cv::Mat near = dist <= tolerance + 1e-3;
  return cv::countNonZero(near & boundary);
}

// Per image, per label: pixel counts and the bounding box of the label's
// pixels in the ground truth or the prediction (valid pixels only).
struct ImageClass {
  int64_t gt = 0, pred = 0, intersection = 0;
  int x0 = INT_MAX, y0 = INT_MAX, x1 = -1, y1 = -1;
  void Extend(int x, int y) {
    x0 = std::min(x0, x);
    y0 = std::min(y0, y);
    x1 = std::max(x1, x);
    y1 = std::max(y1, y);
  }
};

}  // namespace

Image<uint8_t> BoundaryBand(const Image<uint8_t>& mask, int d) {
  CheckArgument(d >= 1, "BoundaryBand: the band width must be >= 1");
  cv::Mat m(mask.height(), mask.width(), CV_8U);
  for (int y = 0; y < mask.height(); ++y) {
    for (int x = 0; x < mask.width(); ++x) {
      m.at<uint8_t>(y, x) = mask(x, y) ? 255 : 0;
    }
  }
  const cv::Mat band = Band(m, d);
  Image<uint8_t> out(mask.width(), mask.height());
  for (int y = 0; y < mask.height(); ++y) {
    for (int x = 0; x < mask.width(); ++x) {
      out(x, y) = band.at<uint8_t>(y, x) ? 1 : 0;
    }
  }
  return out;
}

SegEvaluator::SegEvaluator(const SegEvalOptions& options) : options_(options) {
  options_.Check();
}

bool SegEvaluator::IsClass(uint16_t label) const {
  return !(options_.ignore_zero && label == 0) &&
         !(options_.ignore_label >= 0 && label == options_.ignore_label);
}

void SegEvaluator::Add(const LabelMap& pred, const LabelMap& gt) {
  CheckArgument(pred.SameSize(gt),
                "eval seg: prediction is " + std::to_string(pred.width()) +
                    "x" + std::to_string(pred.height()) + ", ground truth " +
                    std::to_string(gt.width()) + "x" +
                    std::to_string(gt.height()));
  CheckArgument(pred.channels() == 1 && gt.channels() == 1,
                "eval seg: label maps must have one channel");
  const int w = gt.width(), h = gt.height();
  // One pass for the counts and each label's extent; a flat table indexed by
  // label avoids a map lookup per pixel.
  std::vector<int> slot(65536, -1);
  std::vector<uint16_t> labels;
  std::vector<ImageClass> local;
  const auto get = [&](uint16_t label) -> ImageClass& {
    if (slot[label] < 0) {
      slot[label] = static_cast<int>(local.size());
      labels.push_back(label);
      local.emplace_back();
    }
    return local[slot[label]];
  };
  int64_t valid = 0, correct = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const uint16_t g = gt(x, y);
      if (!IsClass(g)) continue;  // Unlabelled: the prediction is not scored.
      ++valid;
      const uint16_t p = pred(x, y);
      ImageClass& gc = get(g);
      ++gc.gt;
      gc.Extend(x, y);
      if (p == g) {
        ++correct;
        ++gc.pred;
        ++gc.intersection;
      } else if (IsClass(p)) {
        // A predicted 0 / ignore label is simply wrong, not a class.
        ImageClass& pc = get(p);
        ++pc.pred;
        pc.Extend(x, y);
      }
    }
  }
  valid_ += valid;
  correct_ += correct;
  ++images_;

  const int d = BoundaryBandWidth(options_.boundary_dilation_ratio, w, h);
  // Margin around a class's extent so that the crop's edges lie outside the
  // erosion windows of its pixels (the crop then behaves like the whole
  // image; at the image border the constant-0 border matches the
  // reference's zero padding).
  const int margin = d + 1;
  for (size_t k = 0; k < labels.size(); ++k) {
    const uint16_t c = labels[k];
    const ImageClass& ic = local[k];
    Counts& total = counts_[c];
    total.intersection += ic.intersection;
    total.gt += ic.gt;
    total.pred += ic.pred;

    const int x0 = std::max(0, ic.x0 - margin),
              y0 = std::max(0, ic.y0 - margin);
    const int x1 = std::min(w - 1, ic.x1 + margin),
              y1 = std::min(h - 1, ic.y1 + margin);
    cv::Mat g_mask = cv::Mat::zeros(y1 - y0 + 1, x1 - x0 + 1, CV_8U);
    cv::Mat p_mask = g_mask.clone();
    for (int y = y0; y <= y1; ++y) {
      uint8_t* g_row = g_mask.ptr<uint8_t>(y - y0);
      uint8_t* p_row = p_mask.ptr<uint8_t>(y - y0);
      for (int x = x0; x <= x1; ++x) {
        if (!IsClass(gt(x, y))) continue;  // Masks cover valid pixels only.
        g_row[x - x0] = gt(x, y) == c ? 255 : 0;
        p_row[x - x0] = pred(x, y) == c ? 255 : 0;
      }
    }
    const cv::Mat g_band = Band(g_mask, d), p_band = Band(p_mask, d);
    total.band_intersection += cv::countNonZero(g_band & p_band);
    total.band_union += cv::countNonZero(g_band | p_band);

    const cv::Mat g_contour = d == 1 ? g_band : Band(g_mask, 1);
    const cv::Mat p_contour = d == 1 ? p_band : Band(p_mask, 1);
    total.pred_contour += cv::countNonZero(p_contour);
    total.gt_contour += cv::countNonZero(g_contour);
    total.pred_contour_matched +=
        MatchedWithin(p_contour, g_contour, options_.boundary_tolerance_px);
    total.gt_contour_matched +=
        MatchedWithin(g_contour, p_contour, options_.boundary_tolerance_px);
  }
}

SegMetrics SegEvaluator::Result() const {
  SegMetrics m;
  m.images = images_;
  m.valid_pixels = valid_;
  m.pixel_accuracy =
      valid_ ? static_cast<double>(correct_) / static_cast<double>(valid_)
             : 0.0;
  int n_iou = 0, n_acc = 0, n_biou = 0, n_bf = 0;
  for (const auto& [id, k] : counts_) {
    ClassSegMetrics c;
    c.id = id;
    c.intersection = k.intersection;
    c.gt_pixels = k.gt;
    c.pred_pixels = k.pred;
    c.union_pixels = k.gt + k.pred - k.intersection;
    if (c.union_pixels == 0) continue;
    c.iou = static_cast<double>(k.intersection) /
            static_cast<double>(c.union_pixels);
    m.mean_iou += c.iou;
    ++n_iou;
    if (k.gt > 0) {
      c.accuracy =
          static_cast<double>(k.intersection) / static_cast<double>(k.gt);
      m.mean_accuracy += c.accuracy;
      ++n_acc;
    }
    c.boundary_intersection = k.band_intersection;
    c.boundary_union = k.band_union;
    if (k.band_union > 0) {
      c.boundary_iou = static_cast<double>(k.band_intersection) /
                       static_cast<double>(k.band_union);
      m.mean_boundary_iou += c.boundary_iou;
      ++n_biou;
    }
    if (k.pred_contour > 0) {
      c.boundary_precision = static_cast<double>(k.pred_contour_matched) /
                             static_cast<double>(k.pred_contour);
    }
    if (k.gt_contour > 0) {
      c.boundary_recall = static_cast<double>(k.gt_contour_matched) /
                          static_cast<double>(k.gt_contour);
    }
    if (k.pred_contour + k.gt_contour > 0) {
      const double s = c.boundary_precision + c.boundary_recall;
      c.boundary_f =
          s > 0 ? 2 * c.boundary_precision * c.boundary_recall / s : 0.0;
      m.mean_boundary_f += c.boundary_f;
      ++n_bf;
    }
    m.classes.push_back(c);
  }
  if (n_iou) m.mean_iou /= n_iou;
  if (n_acc) m.mean_accuracy /= n_acc;
  if (n_biou) m.mean_boundary_iou /= n_biou;
  if (n_bf) m.mean_boundary_f /= n_bf;
  return m;
}

std::vector<std::pair<fs::path, fs::path>> MatchSegFiles(
    const fs::path& pred_dir, const fs::path& gt_dir, bool allow_missing) {
  RequireDirectory(pred_dir, "prediction folder");
  RequireDirectory(gt_dir, "ground-truth folder");
  std::vector<fs::path> gts;
  for (const auto& e : fs::directory_iterator(gt_dir)) {
    if (e.is_regular_file() && e.path().extension() == ".png") {
      gts.push_back(e.path());
    }
  }
  if (gts.empty()) throw IoError(gt_dir, "no ground-truth PNG files");
  std::sort(gts.begin(), gts.end());
  std::vector<std::pair<fs::path, fs::path>> pairs;
  for (const fs::path& g : gts) {
    const std::string stem = g.stem().string();
    const fs::path candidates[] = {pred_dir / (stem + ".png"),
                                   pred_dir / (stem + "_semantic.png"),
                                   pred_dir / "semantic" / (stem + ".png")};
    const auto it =
        std::find_if(std::begin(candidates), std::end(candidates),
                     [](const fs::path& p) { return fs::is_regular_file(p); });
    if (it != std::end(candidates)) {
      pairs.emplace_back(*it, g);
    } else if (!allow_missing) {
      throw IoError(pred_dir / (stem + ".png"),
                    fmt::format("no prediction for ground truth {} (also "
                                "looked for {}_semantic.png and "
                                "semantic/{}.png)",
                                g.string(), stem, stem));
    }
  }
  if (pairs.empty()) {
    throw IoError(pred_dir, "no prediction matches a ground-truth file of " +
                                gt_dir.string());
  }
  return pairs;
}

size_t FoldUnnamedIntoCatchAll(const LabelSet& labels, LabelMap* gt) {
  if (!labels.Contains(0) || labels.Get(0).kind != ClassKind::kOther) {
    return 0;
  }
  size_t changed = 0;
  for (uint16_t& v : gt->values()) {
    if (v != 0 && !labels.Contains(v)) v = 0, ++changed;
  }
  return changed;
}

}  // namespace semrec::eval
