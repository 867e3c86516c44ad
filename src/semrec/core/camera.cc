#include "semrec/core/camera.h"

#include <cmath>

#include <fmt/format.h>

#include "semrec/core/error.h"

namespace semrec {

void CameraIntrinsics::Check() const {
  CheckArgument(
      width > 0 && height > 0,
      fmt::format("camera intrinsics: image size must be positive, got {}x{}",
                  width, height));
  CheckArgument(
      std::isfinite(fx) && std::isfinite(fy) && fx > 0.0 && fy > 0.0,
      fmt::format(
          "camera intrinsics: focal lengths must be positive, got fx={} fy={}",
          fx, fy));
  CheckArgument(std::isfinite(cx) && std::isfinite(cy),
                "camera intrinsics: principal point must be finite");
}

Eigen::Matrix3d CameraIntrinsics::K() const {
  Eigen::Matrix3d k;
  k << fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0;
  return k;
}

CameraIntrinsics CameraIntrinsics::Scaled(double scale) const {
  CheckArgument(scale > 0.0, "CameraIntrinsics::Scaled: scale must be > 0");
  CameraIntrinsics out = *this;
  out.width = static_cast<int>(std::lround(width * scale));
  out.height = static_cast<int>(std::lround(height * scale));
  // Pixel centres at integer coordinates: the continuous image edge is at -0.5.
  out.fx = fx * scale;
  out.fy = fy * scale;
  out.cx = (cx + 0.5) * scale - 0.5;
  out.cy = (cy + 0.5) * scale - 0.5;
  return out;
}

std::string CameraIntrinsics::ToString() const {
  return fmt::format("{}x{} fx={:.3f} fy={:.3f} cx={:.3f} cy={:.3f}", width,
                     height, fx, fy, cx, cy);
}

}  // namespace semrec
