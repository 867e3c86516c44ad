// Synthetic scene generation speed: ray casting, noise and PNG encoding per
// frame, on one core, for the six-objects preset at 640x480 (issue target: 100
// frames well under 10 s on one core).
//   bench_synth [frames=100] [preset=six-objects]
#include <cstdio>
#include <string>

#include <tbb/global_control.h>

#include "semrec/core/image.h"
#include "semrec/core/stopwatch.h"
#include "semrec/io/image_io.h"
#include "semrec/synth/generator.h"
#include "semrec/synth/render.h"

namespace {

// Seconds on one clock for the whole run (differences between calls).
const semrec::Stopwatch kClock;
double Now() { return kClock.Elapsed(); }

}  // namespace

int main(int argc, char** argv) {
  using namespace semrec;
  const int frames = argc > 1 ? std::stoi(argv[1]) : 100;
  const std::string preset = argc > 2 ? argv[2] : "six-objects";
  synth::SynthOptions options = synth::SynthOptions::Preset(preset);
  options.frames = frames;
  options.scene.seed = options.seed;
  const synth::Scene scene = synth::GenerateScene(options.scene);
  const CameraIntrinsics k = options.Intrinsics();
  const auto poses = synth::MakeTrajectory(scene, options.trajectory, frames,
                                           options.fps, options.seed);

  double t_render = 0, t_noise = 0, t_png = 0;
  const std::filesystem::path tmp =
      std::filesystem::temp_directory_path() / "semrec_bench_synth";
  for (int i = 0; i < frames; ++i) {
    double t0 = Now();
    const synth::RenderedFrame r =
        synth::Render(scene, i / options.fps, poses[i], k);
    double t1 = Now();
    const DepthImage noisy =
        synth::ApplyDepthNoise(r.depth, r.cos_incidence, k, options.noise, i);
    double t2 = Now();
    io::WritePng(tmp / "c.png", r.color);
    DepthImage16 raw(k.width, k.height, 1);
    for (size_t p = 0; p < raw.NumPixels(); ++p) {
      raw.values()[p] = static_cast<uint16_t>(noisy.values()[p] * 5000);
    }
    io::WritePng(tmp / "d.png", raw);
    io::WritePng(tmp / "s.png", r.semantic);
    io::WritePng(tmp / "i.png", r.instance);
    double t3 = Now();
    t_render += t1 - t0, t_noise += t2 - t1, t_png += t3 - t2;
  }
  std::filesystem::remove_all(tmp);

  // The whole generator (all layers + ground truth) on one thread, and on all
  // cores.
  double whole_1 = 0, whole_n = 0;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    synth::SynthOptions o = options;
    o.overwrite = true;
    ProgressOptions quiet;
    quiet.mode = ProgressOptions::Mode::kOff;
    whole_1 = synth::WriteSyntheticSequence(o, tmp, quiet).seconds;
  }
  {
    synth::SynthOptions o = options;
    o.overwrite = true;
    ProgressOptions quiet;
    quiet.mode = ProgressOptions::Mode::kOff;
    whole_n = synth::WriteSyntheticSequence(o, tmp, quiet).seconds;
  }
  std::filesystem::remove_all(tmp);

  std::printf("synth benchmark: preset %s, %d frames %dx%d\n", preset.c_str(),
              frames, k.width, k.height);
  std::printf("  ray casting            %7.3f s  (%6.1f ms/frame)\n", t_render,
              1e3 * t_render / frames);
  std::printf("  depth noise            %7.3f s  (%6.1f ms/frame)\n", t_noise,
              1e3 * t_noise / frames);
  std::printf("  PNG encode (4 images)  %7.3f s  (%6.1f ms/frame)\n", t_png,
              1e3 * t_png / frames);
  std::printf(
      "  render + noise, 1 core %7.3f s  (target: well under 10 s per 100 "
      "frames)\n",
      t_render + t_noise);
  std::printf(
      "  full generator, 1 core %7.3f s  (all 6 layers + ground truth)\n",
      whole_1);
  std::printf("  full generator, all    %7.3f s  (speed-up %.2fx)\n", whole_n,
              whole_1 / whole_n);
  return 0;
}
