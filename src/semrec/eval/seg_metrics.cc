#include "semrec/eval/seg_metrics.h"

#include <algorithm>
#include <cmath>
#include <set>

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

SegEvaluator::SegEvaluator(const SegEvalOptions& options) : options_(options) {
  options_.Check();
}

Image<uint8_t> BoundaryBand(const Image<uint8_t>& mask, int d) {
  const int w = mask.width(), h = mask.height();
  cv::Mat padded = cv::Mat::zeros(h + 2, w + 2, CV_8U);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x)
      padded.at<uint8_t>(y + 1, x + 1) = mask(x, y) ? 1 : 0;
  }
  cv::Mat eroded;
  cv::erode(padded, eroded, cv::Mat::ones(3, 3, CV_8U), cv::Point(-1, -1),
            std::max(d, 1), cv::BORDER_CONSTANT, cv::Scalar(0));
  Image<uint8_t> band(w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      band(x, y) =
          padded.at<uint8_t>(y + 1, x + 1) && !eroded.at<uint8_t>(y + 1, x + 1);
    }
  }
  return band;
}

namespace {

// Pixels of `boundary` within `tolerance` of a pixel of `other`.
int64_t MatchedWithin(const Image<uint8_t>& boundary,
                      const Image<uint8_t>& other, int tolerance,
                      int64_t* total) {
  const int w = boundary.width(), h = boundary.height();
  // Distance to the nearest `other` boundary pixel (0 on it).
  cv::Mat src(h, w, CV_8U);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) src.at<uint8_t>(y, x) = other(x, y) ? 0 : 255;
  }
  cv::Mat dist;
  cv::distanceTransform(src, dist, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  int64_t matched = 0;
  *total = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (!boundary(x, y)) continue;
      ++*total;
      matched += dist.at<float>(y, x) <= tolerance + 1e-4f;
    }
  }
  return matched;
}

}  // namespace

void SegEvaluator::Add(const LabelMap& pred, const LabelMap& gt) {
  CheckArgument(pred.SameSize(gt),
                "eval seg: prediction is " + std::to_string(pred.width()) +
                    "x" + std::to_string(pred.height()) + ", ground truth " +
                    std::to_string(gt.width()) + "x" +
                    std::to_string(gt.height()));
  const int w = gt.width(), h = gt.height();
  const auto ignored = [&](uint16_t g) {
    return (options_.ignore_zero && g == 0) ||
           (options_.ignore_label >= 0 && g == options_.ignore_label);
  };
  std::set<uint16_t> present;
  for (size_t i = 0; i < gt.NumPixels(); ++i) {
    const uint16_t g = gt.values()[i], p = pred.values()[i];
    if (ignored(g)) continue;
    ++valid_;
    ++counts_[g].gt;
    ++counts_[p].pred;
    present.insert(g);
    present.insert(p);
    if (g == p) {
      ++correct_;
      ++counts_[g].intersection;
    }
  }
  ++images_;
  // Boundaries per class present, on masks restricted to valid pixels.
  const int d =
      std::max(1, int(std::lround(options_.boundary_dilation_ratio *
                                  std::sqrt(double(w) * w + double(h) * h))));
  for (uint16_t c : present) {
    Image<uint8_t> g_mask(w, h), p_mask(w, h);
    for (size_t i = 0; i < gt.NumPixels(); ++i) {
      const bool valid = !ignored(gt.values()[i]);
      g_mask.values()[i] = valid && gt.values()[i] == c;
      p_mask.values()[i] = valid && pred.values()[i] == c;
    }
    const Image<uint8_t> gb = BoundaryBand(g_mask, d);
    const Image<uint8_t> pb = BoundaryBand(p_mask, d);
    Counts& k = counts_[c];
    for (size_t i = 0; i < gb.NumPixels(); ++i) {
      k.b_inter += gb.values()[i] && pb.values()[i];
      k.b_union += gb.values()[i] || pb.values()[i];
    }
    const Image<uint8_t> gc = BoundaryBand(g_mask, 1);
    const Image<uint8_t> pc = BoundaryBand(p_mask, 1);
    int64_t total = 0;
    k.pred_b_matched +=
        MatchedWithin(pc, gc, options_.boundary_tolerance_px, &total);
    k.pred_b += total;
    k.gt_b_matched +=
        MatchedWithin(gc, pc, options_.boundary_tolerance_px, &total);
    k.gt_b += total;
  }
}

SegMetrics SegEvaluator::Result() const {
  SegMetrics m;
  m.images = images_;
  m.valid_pixels = valid_;
  m.pixel_accuracy = valid_ ? double(correct_) / valid_ : 0.0;
  int n_iou = 0, n_acc = 0, n_biou = 0, n_bf = 0;
  for (const auto& [id, k] : counts_) {
    if (k.gt + k.pred == 0) continue;
    ClassSegMetrics c;
    c.id = id;
    c.intersection = k.intersection;
    c.gt_pixels = k.gt;
    c.pred_pixels = k.pred;
    c.iou = double(k.intersection) / double(k.gt + k.pred - k.intersection);
    m.mean_iou += c.iou;
    ++n_iou;
    if (k.gt > 0) {
      c.accuracy = double(k.intersection) / double(k.gt);
      m.mean_accuracy += c.accuracy;
      ++n_acc;
    }
    c.boundary_intersection = k.b_inter;
    c.boundary_union = k.b_union;
    if (k.b_union > 0) {
      c.boundary_iou = double(k.b_inter) / double(k.b_union);
      m.mean_boundary_iou += c.boundary_iou;
      ++n_biou;
    }
    c.boundary_precision = k.pred_b ? double(k.pred_b_matched) / k.pred_b : 0.0;
    c.boundary_recall = k.gt_b ? double(k.gt_b_matched) / k.gt_b : 0.0;
    if (k.pred_b + k.gt_b > 0) {
      const double s = c.boundary_precision + c.boundary_recall;
      c.boundary_f =
          s > 0 ? 2 * c.boundary_precision * c.boundary_recall / s : 0;
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
    const fs::path& pred_dir, const fs::path& gt_dir) {
  RequireDirectory(pred_dir, "prediction folder");
  RequireDirectory(gt_dir, "ground-truth folder");
  std::vector<fs::path> gts;
  for (const auto& e : fs::directory_iterator(gt_dir)) {
    if (e.is_regular_file() && e.path().extension() == ".png")
      gts.push_back(e.path());
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
    if (it == std::end(candidates)) {
      throw IoError(pred_dir / (stem + ".png"),
                    "no prediction for ground truth " + g.string());
    }
    pairs.emplace_back(*it, g);
  }
  return pairs;
}

}  // namespace semrec::eval
