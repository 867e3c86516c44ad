#include "semrec/core/image.h"

namespace semrec {

DepthImage DepthToMeters(const DepthImage16& raw, double depth_scale,
                         uint16_t invalid_value, double max_depth_m) {
  CheckArgument(depth_scale > 0.0, "DepthToMeters: depth_scale must be > 0");
  CheckArgument(raw.channels() == 1,
                "DepthToMeters: depth must have one channel");
  DepthImage out(raw.width(), raw.height(), 1, 0.0f);
  const uint16_t* in = raw.data();
  float* dst = out.data();
  const auto scale = static_cast<float>(depth_scale);
  for (size_t i = 0; i < raw.NumPixels(); ++i) {
    if (in[i] == 0 || in[i] == invalid_value) continue;
    // Same arithmetic as Open3D's ConvertDepthToFloatImage (float division) so
    // that results match Open3D's integration bit for bit.
    const float d = static_cast<float>(in[i]) / scale;
    if (max_depth_m > 0.0 && d >= max_depth_m) continue;
    dst[i] = d;
  }
  return out;
}

}  // namespace semrec
