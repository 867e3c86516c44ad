// A Kinect-like depth noise model (Nguyen, Izadi, Lovell 2012; Khoshelham &
// Elberink 2012): axial noise growing with depth, lateral noise, disparity
// quantisation, dropouts at grazing angles and at depth edges, and a
// maximum-depth cut-off.
#pragma once

#include <cstdint>

#include "semrec/core/camera.h"
#include "semrec/core/image.h"

namespace semrec::synth {

struct DepthNoiseOptions {
  /// Off: depth is exact (only the max-depth cut-off applies).
  bool enabled = true;
  /// Scales the axial and lateral sigmas (1 = the published model).
  double strength = 1.0;
  /// Stereo baseline of the structured-light sensor (Kinect v1: 7.5 cm).
  double baseline_m = 0.075;
  /// Disparity resolution in pixels (Kinect v1: 1/8 px); 0 disables
  /// quantisation.
  double disparity_step_px = 0.125;
  /// Lateral noise (pixels) at strength 1.
  double lateral_sigma_px = 0.5;
  /// Surfaces seen at more than this angle from their normal return no depth.
  double max_incidence_deg = 78.0;
  /// The far side of a depth jump larger than edge_jump_m + edge_jump_rel * z
  /// returns no depth.
  double edge_jump_m = 0.05;
  double edge_jump_rel = 0.02;
  /// Depth at or beyond this returns nothing (also applied when noise is off).
  double max_depth_m = 4.0;

  void Check() const;
};

/// Axial standard deviation at depth z (m): 0.0012 + 0.0019 (z - 0.4)^2.
double KinectAxialSigmaM(double z_m);

/// Noisy copy of `clean`. Deterministic for a given `seed`.
DepthImage ApplyDepthNoise(const DepthImage& clean,
                           const Image<float>& cos_incidence,
                           const CameraIntrinsics& k,
                           const DepthNoiseOptions& options, uint64_t seed);

}  // namespace semrec::synth
