// `semrec synth`: writes a synthetic RGB-D sequence in the generic layout with
// full ground truth (see docs/usage.md, "Synthetic scenes", for every file, its
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
#include "semrec/synth/trajectory.h"

namespace semrec::synth {

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
  /// Samples within this distance of another object's solid are left out of
  /// the ground truth: a bed's underside on the floor, a headboard's back
  /// against the wall, the wall behind it. No camera sees them, yet at the
  /// contact line they lie within the depth tolerance of `eval scene
  /// --observed-in` and would be scored as seen.
  double gt_hidden_contact_m = 0.01;
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
