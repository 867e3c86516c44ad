#include "semrec/detect/box.h"

#include <algorithm>
#include <cmath>

namespace semrec::detect {

double CornerDistance(const Box& a, const Box& b) {
  const double dl = a.left - b.left, dt = a.top - b.top;
  const double dr = (a.left + a.width) - (b.left + b.width);
  const double db = (a.top + a.height) - (b.top + b.height);
  return std::hypot(dl, dt) + std::hypot(dr, dt) + std::hypot(dl, db) +
         std::hypot(dr, db);
}

double Iou(const Box& a, const Box& b) {
  const double w =
      std::min(a.left + a.width, b.left + b.width) - std::max(a.left, b.left);
  const double h =
      std::min(a.top + a.height, b.top + b.height) - std::max(a.top, b.top);
  if (w <= 0 || h <= 0) return 0.0;
  const double inter = w * h;
  const double uni = a.width * a.height + b.width * b.height - inter;
  return uni > 0.0 ? inter / uni : 0.0;
}

}  // namespace semrec::detect
