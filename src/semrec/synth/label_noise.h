// Labels that behave like a real segmenter's: the synthetic ground truth is
// one clean mask per object in every view, which no mask generator delivers.
// Per view (seeded by the view), objects are cut into parts (along their
// primitives - a chair's seat, back, legs - or by random planes through their
// centre), joined with a touching neighbour, given another object class,
// boundaries are jittered and small masks dropped. Fusion's evidence merging
// is measured against this; so is the paper's rule alone.
// Optionally object pixels bleed into the structure they touch (a chair's legs
// painted as floor, a cabinet's side as wall), the same parts in most views.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

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
  /// Share of the objects with several primitives that a mask generator cuts
  /// the same way in every view (SAM gives a chair's back, a sofa's cushions,
  /// a table's top as masks of their own: 7-Scenes chess's chair piece was
  /// held apart by 14 of 20 views). Such an object (a hash of the scene seed)
  /// is cut along a fixed grouping of its primitives in 80 % of the views
  /// where it is not joined to a neighbour, instead of the per-view split
  /// above. 0: none (the labels are those without this option).
  double consistent_cut_share = 0.0;
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

  /// Structure bleed: object pixels near structure take the class and the
  /// mask of the floor or wall nearest to them (in 3D, among those in view),
  /// as a 2D segmenter paints the lower part of a chair as floor or a cabinet
  /// against a wall as wall. Candidates are object pixels within
  /// bleed_contact_m of the floor or a wall, or darker than bleed_dark_luma.
  /// Whether a candidate bleeds is decided per object side (object x the
  /// floor or wall it bleeds into: all of a chair's legs at once),
  /// correlated across views: share / 0.8 of the sides (a hash of the scene
  /// seed and the side) bleed, each in 80 % of the views (a per-view draw);
  /// shares above 0.8 make every side bleed in that share of the views.
  bool bleed = false;
  /// Expected share of the candidate pixels that bleed.
  double bleed_share = 0.3;
  double bleed_contact_m = 0.2;
  /// Rec. 601 luma (0-255) below which an object pixel is a candidate.
  double bleed_dark_luma = 40.0;
  /// Objects of these classes look like the wall to a 2D model (a row of
  /// base cabinets; 7-Scenes chess's are called wall in nearly every view):
  /// with bleed on, all their pixels take the class and mask of the wall
  /// nearest to them, every side in 80 % of the views (the bleed share does
  /// not apply).
  std::vector<std::string> bleed_wall_lookalikes = {"counter"};

  /// Throws InvalidArgument for probabilities or shares outside [0, 1] or
  /// negative sizes.
  void Check() const;
};

struct NoisyLabels {
  LabelMap semantic;
  /// Fresh instance ids per view (1..n); structure keeps one mask per face and
  /// people their ground-truth instance.
  LabelMap instance;
};

/// Noisy labels for one rendered view; deterministic in `seed` (this view's)
/// and `scene_seed` (the same for every view of a sequence: what holds across
/// views). The bleed takes no draws from the other steps' stream, so turning it
/// on changes only the bled pixels (and what jitter and dropping make of them).
NoisyLabels ApplyLabelNoise(const RenderedFrame& frame, const Scene& scene,
                            const Transform& T_world_camera,
                            const CameraIntrinsics& k,
                            const LabelNoiseOptions& options, uint64_t seed,
                            uint64_t scene_seed);

}  // namespace semrec::synth
