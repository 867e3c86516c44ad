// `semrec synth`: writes a synthetic RGB-D sequence in the generic layout with
// full ground truth (see README.md, "Synthetic scenes", for every file, its
// format, frames and units).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "semrec/core/camera.h"
#include "semrec/core/progress.h"
#include "semrec/core/transform.h"
#include "semrec/synth/label_noise.h"
#include "semrec/synth/noise.h"
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

  void Check() const;
};

struct SynthOptions {
  SceneOptions scene;
  TrajectoryOptions trajectory;
  DepthNoiseOptions noise;
  int frames = 60;
  double fps = 30.0;
  int width = 640;
  int height = 480;
  double fx = 525.0;
  double fy = 525.0;
  /// Seeds the scene, the trajectory jitter and the noise; identical seeds give
  /// identical bytes.
  uint64_t seed = 1;
  /// Spacing of the dense ground-truth surface samples: objects and people-free
  /// structure.
  double gt_object_spacing_m = 0.005;
  double gt_structure_spacing_m = 0.02;
  /// Also write segmenter-like labels (synth/label_noise.h) to
  /// labels_noisy/{instance,semantic}/ with labels_noisy/classes.json, a
  /// folder `semrec fuse|mesh --labels` reads.
  bool write_noisy_labels = false;
  LabelNoiseOptions label_noise;
  /// Allow writing into a non-empty output folder (files are replaced).
  bool overwrite = false;

  /// Throws InvalidArgument for bad values (zero frames, negative noise, ...).
  void Check() const;
  CameraIntrinsics Intrinsics() const;

  /// "six-objects", "people" or "office". Throws InvalidArgument for an unknown
  /// name.
  static SynthOptions Preset(const std::string& name);
  static std::vector<std::string> PresetNames();
};

/// Camera poses (T_world_camera) for frames at times i / fps. They depend on
/// time only, so a shorter sequence is a prefix of a longer one.
std::vector<Transform> MakeTrajectory(const Scene& scene,
                                      const TrajectoryOptions& options,
                                      int frames, double fps, uint64_t seed);

struct SynthSummary {
  size_t frames = 0;
  std::map<std::string, int> objects_per_class;
  int people = 0;
  /// Frames in which 0, 1, 2, ... people are visible.
  std::map<int, int> frames_with_people;
  uint64_t bytes_written = 0;
  double seconds = 0.0;
};

/// Generates the scene and writes the sequence and its ground truth into
/// `out_dir`. Refuses a non-empty folder unless options.overwrite. Every file
/// is written atomically.
SynthSummary WriteSyntheticSequence(const SynthOptions& options,
                                    const std::filesystem::path& out_dir,
                                    const ProgressOptions& progress = {});

}  // namespace semrec::synth
