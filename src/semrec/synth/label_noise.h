// Labels that behave like a real segmenter's: the synthetic ground truth is
// one clean mask per object in every view, which no mask generator delivers.
// Per view (seeded by the view), objects are cut into parts (along their
// primitives - a chair's seat, back, legs - or by random planes through their
// centre), joined with a touching neighbour, given another object class,
// boundaries are jittered and small masks dropped. Fusion's evidence merging
// is measured against this (issue 17); so is the paper's rule alone.
#pragma once

#include <cstdint>

#include "semrec/core/camera.h"
#include "semrec/core/label_map.h"
#include "semrec/core/transform.h"
#include "semrec/synth/render.h"
#include "semrec/synth/scene.h"

namespace semrec::synth {

struct LabelNoiseOptions {
  /// Per object and view: the mask is cut in two or three (half the time
  /// along the object's primitives when it has several, else by random planes
  /// through its centre).
  double split_probability = 0.6;
  /// Per object and view: the mask joins a touching neighbour's (the pair takes
  /// the larger mask's class).
  double merge_probability = 0.05;
  /// Per mask and view: another object class from the scene.
  double class_flip_probability = 0.1;
  /// Pixels within this distance of a mask boundary take a random nearby
  /// pixel's labels with probability 1/2 (0: clean boundaries).
  int jitter_px = 2;
  /// Object masks with fewer pixels are dropped (instance 0).
  int min_mask_pixels = 150;

  /// Throws InvalidArgument for probabilities outside [0, 1] or negative
  /// sizes.
  void Check() const;
};

struct NoisyLabels {
  LabelMap semantic;
  /// Fresh instance ids per view (1..n); structure keeps one mask per face and
  /// people their ground-truth instance.
  LabelMap instance;
};

/// Noisy labels for one rendered view; deterministic in `seed`.
NoisyLabels ApplyLabelNoise(const RenderedFrame& frame, const Scene& scene,
                            const Transform& T_world_camera,
                            const CameraIntrinsics& k,
                            const LabelNoiseOptions& options, uint64_t seed);

}  // namespace semrec::synth
