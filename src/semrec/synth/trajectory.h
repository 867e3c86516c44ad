// Camera trajectories of the synthetic sequences: smooth video-like paths
// (orbit, walk-through, static) and sparse independent views.
#pragma once

#include <cstdint>
#include <vector>

#include "semrec/core/transform.h"
#include "semrec/synth/scene.h"

namespace semrec::synth {

struct TrajectoryOptions {
  enum class Kind {
    /// Circles the room centre above the furniture, looking down at it.
    kOrbit,
    /// Travels along the room's long axis, panning left and right.
    kWalkthrough,
    /// Stands at the front wall looking into the room (people walk through the
    /// view).
    kStatic,
    /// Independent views, as a robot's photos of a house walk-through: each
    /// frame a random position at robot height with a random heading, looking
    /// roughly horizontally, so many objects are seen in one or two views
    /// only. No jitter (the views are unrelated anyway).
    kSparse,
  };
  Kind kind = Kind::kOrbit;
  /// Camera height for orbit and walk-through (above the tallest furniture, 1.8
  /// m).
  double height_m = 2.1;
  /// Orbit: angular speed (60 degrees/s = 2 degrees per frame at 30 fps, a
  /// brisk hand-held pan).
  double orbit_deg_per_s = 60.0;
  /// Walk-through: speed along the room.
  double walking_speed_mps = 0.5;
  /// Hand-held jitter amplitudes (smooth, seeded).
  double jitter_m = 0.01;
  double jitter_deg = 0.5;

  /// Sparse: camera height range (uniform), a robot's camera.
  double sparse_min_height_m = 0.6;
  double sparse_max_height_m = 1.2;
  /// Sparse: pitch below the horizon, uniform in [0, this]; no roll.
  double sparse_max_pitch_deg = 15.0;
  /// Sparse: least distance from the camera to the walls, to every object's
  /// bounding box and to people (at the frame's time).
  double sparse_clearance_m = 0.3;
  /// Sparse: the median distance along a grid of probe rays (the central 48 x
  /// 36 degrees of the view) must lie in this range: no view into a wall at
  /// 10 cm, none into the far empty distance.
  double sparse_min_median_depth_m = 1.0;
  double sparse_max_median_depth_m = 3.5;
  /// Sparse: at least this share of the probe rays hits an object (the view
  /// looks at something, not only at floor and walls).
  double sparse_min_object_share = 0.1;

  void Check() const;
};

/// Camera poses (T_world_camera) for frames at times i / fps. Video kinds
/// depend on time only and sparse views on (seed, frame index) only, so a
/// shorter sequence is a prefix of a longer one. Sparse: the first of up to
/// 400 random tries that keeps the clearance and meets the depth and object
/// conditions, else the free try closest to meeting them (throws Error when no
/// try keeps the clearance).
std::vector<Transform> MakeTrajectory(const Scene& scene,
                                      const TrajectoryOptions& options,
                                      int frames, double fps, uint64_t seed);

}  // namespace semrec::synth
