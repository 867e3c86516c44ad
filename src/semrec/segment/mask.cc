#include "semrec/segment/mask.h"

#include <algorithm>
#include <numeric>

#include <opencv2/imgproc.hpp>

#include "semrec/core/error.h"

namespace semrec::segment {

double BoxIoU(const Box& a, const Box& b) {
  const Box inter{std::max(a.x0, b.x0), std::max(a.y0, b.y0),
                  std::min(a.x1, b.x1), std::min(a.y1, b.y1)};
  const int64_t i = inter.area();
  const int64_t u = a.area() + b.area() - i;
  return u > 0 ? static_cast<double>(i) / static_cast<double>(u) : 0.0;
}

Image<uint8_t> Mask::ToImage() const {
  Image<uint8_t> out(image_width, image_height);
  for (int y = box.y0; y < box.y1; ++y) {
    for (int x = box.x0; x < box.x1; ++x) {
      out(x, y) =
          bits[static_cast<size_t>(y - box.y0) * box.width() + (x - box.x0)];
    }
  }
  return out;
}

void Mask::Centroid(double* x, double* y) const {
  double sx = 0, sy = 0;
  int64_t n = 0;
  for (int v = box.y0; v < box.y1; ++v) {
    for (int u = box.x0; u < box.x1; ++u) {
      if (bits[static_cast<size_t>(v - box.y0) * box.width() + (u - box.x0)]) {
        sx += u + 0.5;
        sy += v + 0.5;
        ++n;
      }
    }
  }
  *x = n ? sx / n : 0.0;
  *y = n ? sy / n : 0.0;
}

void Tighten(Mask* mask) {
  const Box old = mask->box;
  Box tight{old.x1, old.y1, old.x0, old.y0};
  int64_t area = 0;
  for (int y = old.y0; y < old.y1; ++y) {
    for (int x = old.x0; x < old.x1; ++x) {
      if (mask->bits[static_cast<size_t>(y - old.y0) * old.width() +
                     (x - old.x0)]) {
        tight.x0 = std::min(tight.x0, x);
        tight.y0 = std::min(tight.y0, y);
        tight.x1 = std::max(tight.x1, x + 1);
        tight.y1 = std::max(tight.y1, y + 1);
        ++area;
      }
    }
  }
  mask->area = area;
  if (area == 0) {
    mask->box = Box{};
    mask->bits.clear();
    return;
  }
  std::vector<uint8_t> bits(static_cast<size_t>(tight.width()) *
                            tight.height());
  for (int y = tight.y0; y < tight.y1; ++y) {
    for (int x = tight.x0; x < tight.x1; ++x) {
      bits[static_cast<size_t>(y - tight.y0) * tight.width() + (x - tight.x0)] =
          mask->bits[static_cast<size_t>(y - old.y0) * old.width() +
                     (x - old.x0)]
              ? 1
              : 0;
    }
  }
  mask->box = tight;
  mask->bits = std::move(bits);
}

Mask MaskFromImage(const Image<uint8_t>& image) {
  CheckArgument(image.channels() == 1, "MaskFromImage: expected one channel");
  Mask m;
  m.image_width = image.width();
  m.image_height = image.height();
  m.box = Box{0, 0, image.width(), image.height()};
  m.bits = image.values();
  Tighten(&m);
  return m;
}

int64_t MaskIntersection(const Mask& a, const Mask& b) {
  const Box inter{std::max(a.box.x0, b.box.x0), std::max(a.box.y0, b.box.y0),
                  std::min(a.box.x1, b.box.x1), std::min(a.box.y1, b.box.y1)};
  int64_t i = 0;
  for (int y = inter.y0; y < inter.y1; ++y) {
    for (int x = inter.x0; x < inter.x1; ++x) {
      i += a.Contains(x, y) && b.Contains(x, y);
    }
  }
  return i;
}

double MaskIoU(const Mask& a, const Mask& b) {
  const int64_t i = MaskIntersection(a, b);
  const int64_t u = a.area + b.area - i;
  return u > 0 ? static_cast<double>(i) / static_cast<double>(u) : 0.0;
}

float StabilityScore(const std::vector<float>& logits, float threshold,
                     float offset) {
  int64_t inter = 0, uni = 0;
  for (float v : logits) {
    inter += v > threshold + offset;
    uni += v > threshold - offset;
  }
  return uni > 0 ? static_cast<float>(inter) / static_cast<float>(uni) : 1.0f;
}

namespace {

// Components of `bin` (0/255, padded crop) with area < min_area are set to
// `fill`; returns whether anything changed. When every foreground component
// is small the largest is kept (as SAM does), so a small object is not erased.
bool RemoveSmall(cv::Mat* bin, int min_area, bool holes) {
  cv::Mat target = holes ? (*bin == 0) : (*bin != 0);
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(target, labels, stats,
                                                 centroids, holes ? 4 : 8);
  std::vector<uint8_t> small(n, 0);
  int largest = 0, kept = 0;
  for (int i = 1; i < n; ++i) {
    const int area = stats.at<int>(i, cv::CC_STAT_AREA);
    small[i] = area < min_area;
    kept += !small[i];
    if (largest == 0 || area > stats.at<int>(largest, cv::CC_STAT_AREA)) {
      largest = i;
    }
  }
  if (!holes && kept == 0 && largest > 0) small[largest] = 0;
  bool changed = false;
  for (int y = 0; y < labels.rows; ++y) {
    const int* row = labels.ptr<int>(y);
    uint8_t* out = bin->ptr<uint8_t>(y);
    for (int x = 0; x < labels.cols; ++x) {
      if (row[x] > 0 && small[row[x]]) {
        out[x] = holes ? 255 : 0;
        changed = true;
      }
    }
  }
  return changed;
}

}  // namespace

void RemoveSmallRegions(Mask* mask, int min_area_px) {
  if (min_area_px <= 0 || mask->area == 0) return;
  // Pad by one pixel so the background around the mask is one component and
  // is never mistaken for a hole.
  const Box b = mask->box;
  cv::Mat bin = cv::Mat::zeros(b.height() + 2, b.width() + 2, CV_8U);
  for (int y = 0; y < b.height(); ++y) {
    for (int x = 0; x < b.width(); ++x) {
      bin.at<uint8_t>(y + 1, x + 1) =
          mask->bits[static_cast<size_t>(y) * b.width() + x] ? 255 : 0;
    }
  }
  bool changed = RemoveSmall(&bin, min_area_px, /*holes=*/true);
  changed |= RemoveSmall(&bin, min_area_px, /*holes=*/false);
  if (!changed) return;
  for (int y = 0; y < b.height(); ++y) {
    for (int x = 0; x < b.width(); ++x) {
      mask->bits[static_cast<size_t>(y) * b.width() + x] =
          bin.at<uint8_t>(y + 1, x + 1) != 0;
    }
  }
  Tighten(mask);
}

// Greedy box NMS, highest score first (ties: input order).
std::vector<Mask> NmsByScore(std::vector<Mask> masks,
                             const std::vector<float>& scores,
                             float threshold) {
  std::vector<size_t> order(masks.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return scores[a] > scores[b]; });
  std::vector<Mask> kept;
  for (size_t i : order) {
    const bool suppressed = std::any_of(
        kept.begin(), kept.end(),
        [&](const Mask& k) { return BoxIoU(k.box, masks[i].box) > threshold; });
    if (!suppressed) kept.push_back(std::move(masks[i]));
  }
  return kept;
}

std::vector<Mask> BoxNms(std::vector<Mask> masks, float threshold) {
  std::vector<float> scores;
  scores.reserve(masks.size());
  for (const Mask& m : masks) scores.push_back(m.predicted_iou);
  return NmsByScore(std::move(masks), scores, threshold);
}

}  // namespace semrec::segment
