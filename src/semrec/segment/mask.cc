#include "semrec/segment/mask.h"

#include <algorithm>

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

}  // namespace semrec::segment
