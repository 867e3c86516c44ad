// Small synthetic scenes for the tests (header only: the test executables
// that include it link semrec_synth).
#pragma once

#include <string>

#include "semrec/core/progress.h"
#include "semrec/synth/generator.h"

namespace semrec::testing {

/// No progress bars or lines in test output.
inline ProgressOptions QuietProgress() {
  ProgressOptions p;
  p.mode = ProgressOptions::Mode::kOff;
  return p;
}

/// A quarter-size (320x240) synthetic sequence with sparse ground truth
/// (5 cm on objects, 20 cm on structure): fast enough for unit tests.
inline synth::SynthOptions SmallScene(const std::string& preset, int frames) {
  synth::SynthOptions o = synth::SynthOptions::Preset(preset);
  o.frames = frames;
  o.width = 320;
  o.height = 240;
  o.fx = o.fy = 262.5;
  o.gt_object_spacing_m = 0.05;
  o.gt_structure_spacing_m = 0.2;
  return o;
}

}  // namespace semrec::testing
