#include "semrec/synth/noise.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "semrec/core/error.h"
#include "semrec/core/random.h"

namespace semrec::synth {

void DepthNoiseOptions::Check() const {
  CheckArgument(std::isfinite(strength) && strength >= 0.0,
                "depth noise: strength must be >= 0 (0 = quantisation and "
                "dropouts only)");
  CheckArgument(baseline_m > 0.0, "depth noise: baseline_m must be > 0");
  CheckArgument(disparity_step_px >= 0.0,
                "depth noise: disparity_step_px must be >= 0");
  CheckArgument(lateral_sigma_px >= 0.0,
                "depth noise: lateral_sigma_px must be >= 0");
  CheckArgument(max_incidence_deg > 0.0 && max_incidence_deg <= 90.0,
                "depth noise: max_incidence_deg must be in (0, 90]");
  CheckArgument(edge_jump_m >= 0.0 && edge_jump_rel >= 0.0,
                "depth noise: edge jump thresholds must be >= 0");
  CheckArgument(max_depth_m > 0.0, "depth noise: max_depth_m must be > 0");
}

double KinectAxialSigmaM(double z) {
  return 0.0012 + 0.0019 * (z - 0.4) * (z - 0.4);
}

DepthImage ApplyDepthNoise(const DepthImage& clean,
                           const Image<float>& cos_incidence,
                           const CameraIntrinsics& k,
                           const DepthNoiseOptions& options, uint64_t seed) {
  options.Check();
  const int w = clean.width(), h = clean.height();
  DepthImage out(w, h, 1, 0.0f);
  if (!options.enabled) {
    for (size_t i = 0; i < clean.NumPixels(); ++i) {
      const float z = clean.values()[i];
      if (z > 0.0f && z < options.max_depth_m) out.values()[i] = z;
    }
    return out;
  }
  Rng rng(seed);
  const double cos_min = std::cos(options.max_incidence_deg * M_PI / 180.0);
  const double lateral = options.lateral_sigma_px * options.strength;
  // The lateral offset is round(lateral * N(0, 1)): a discrete distribution,
  // drawn by inverting its CDF with one 32-bit uniform instead of a normal
  // sample.
  constexpr int kMaxOffset = 8;
  std::array<uint64_t, 2 * kMaxOffset + 1> cdf{};
  for (int o = -kMaxOffset; o <= kMaxOffset; ++o) {
    const double p =
        lateral > 0.0 ? 0.5 * std::erfc(-(o + 0.5) / (lateral * std::sqrt(2.0)))
                      : (o >= 0 ? 1.0 : 0.0);
    cdf[o + kMaxOffset] =
        static_cast<uint64_t>(std::min(p, 1.0) * 4294967296.0);
  }
  cdf.back() = uint64_t{1} << 32;
  auto offset = [&](uint64_t uniform32) {
    int o = 0;
    while (o < 2 * kMaxOffset && uniform32 >= cdf[o]) ++o;
    return o - kMaxOffset;
  };
  const double bf = options.baseline_m * k.fx;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      // Lateral noise: the measurement comes from a slightly displaced pixel.
      const uint64_t bits = rng.Next();
      const int su = std::clamp(u + offset(bits & 0xFFFFFFFFu), 0, w - 1);
      const int sv = std::clamp(v + offset(bits >> 32), 0, h - 1);
      const double n_axial = rng.Normal();
      const double z = clean(su, sv);
      if (z <= 0.0 || cos_incidence(su, sv) < cos_min) continue;
      // Far side of a depth edge: the projector's pattern is shadowed there.
      bool edge = false;
      for (auto [du, dv] : {std::pair{-1, 0}, {1, 0}, {0, -1}, {0, 1}}) {
        const int nu = su + du, nv = sv + dv;
        if (nu < 0 || nv < 0 || nu >= w || nv >= h) continue;
        const double zn = clean(nu, nv);
        if (zn > 0.0 &&
            z - zn > options.edge_jump_m + options.edge_jump_rel * z) {
          edge = true;
        }
      }
      if (edge) continue;
      double noisy = z + options.strength * KinectAxialSigmaM(z) * n_axial;
      if (options.disparity_step_px > 0.0 && noisy > 0.0) {
        const double disparity = bf / noisy;
        const double quantised =
            std::round(disparity / options.disparity_step_px) *
            options.disparity_step_px;
        noisy = quantised > 0.0 ? bf / quantised : 0.0;
      }
      if (noisy > 0.0 && noisy < options.max_depth_m) {
        out(u, v) = static_cast<float>(noisy);
      }
    }
  }
  return out;
}

}  // namespace semrec::synth
