// Camera tracking without poses (odometry/pose_tracker.h) on the real
// recordings: accuracy (ATE RMSE against the recording's own poses, after
// rigid alignment) and time per frame of each method, as ratios against
// frame-to-frame point-to-plane tracking in the same process.
//
//   build/bench/bench_odometry [SEQUENCE [PERSON_MAPS_DIR]] [--frames N]
//
// Without arguments: 7-Scenes chess and Bonn crowd from the sample data.
// PERSON_MAPS_DIR: 16-bit track-id PNGs (`semrec track ... --out DIR`
// writes DIR/persons/<frame>.png); their pixels are left out of tracking.
// Options for sweeps: --only TEXT (methods whose name holds it),
// --downsampling, --max-depth, --keyframe-m, --keyframe-deg,
// --depth-diff, --max-step (PoseTrackerOptions). Environment:
// SEMREC_BONN_PERSON_MAPS (Bonn's person maps in the default run),
// SEMREC_BENCH_SKIP_CHESS, SEMREC_BENCH_WRITE_POSES=DIR (the last run's
// estimate.txt and truth.txt), SEMREC_BENCH_DEBUG (per-frame log).
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "bench_util.h"
#include "semrec/eval/trajectory.h"
#include "semrec/io/image_io.h"
#include "semrec/io/pose_io.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/odometry/pose_tracker.h"

namespace fs = std::filesystem;
using namespace semrec;

namespace {

struct Variant {
  std::string name;
  odometry::PoseTrackerOptions options;
};

int g_downsampling = 0;
double g_max_depth_m = 6.0;
double g_keyframe_m = 0.1, g_keyframe_deg = 10.0;
std::string g_only;
double g_depth_diff_m = 0.07, g_max_step_m = 0.3;

std::vector<Variant> Variants() {
  using O = odometry::PoseTrackerOptions;
  std::vector<Variant> out;
  for (const auto method :
       {O::Method::kFrameToFrame, O::Method::kFrameToKeyframe,
        O::Method::kFrameToModel}) {
    for (const auto loss : {O::Loss::kHybrid, O::Loss::kPhotometric}) {
      Variant v;
      v.options.method = method;
      v.options.loss = loss;
      v.options.image_downsampling = g_downsampling;
      v.options.max_depth_m = g_max_depth_m;
      v.options.keyframe_step_m = g_keyframe_m;
      v.options.keyframe_step_deg = g_keyframe_deg;
      v.options.depth_diff_m = g_depth_diff_m;
      v.options.max_step_m = g_max_step_m;
      v.name = fmt::format("{} {}", odometry::MethodName(method),
                           odometry::LossName(loss));
      if (!g_only.empty() && v.name.find(g_only) == std::string::npos) continue;
      out.push_back(v);
    }
  }
  return out;
}

struct Outcome {
  double ate_m = 0.0, rpe_m = 0.0, seconds_per_frame = 0.0;
  size_t lost = 0;
  std::string error;
};

Outcome Run(const io::SequenceReader& reader, const std::vector<Frame>& frames,
            const std::vector<std::optional<LabelMap>>& masks,
            const odometry::PoseTrackerOptions& options) {
  Outcome out;
  odometry::PoseTracker tracker(options, reader.intrinsics());
  std::vector<io::StampedPose> estimate, truth;
  const Stopwatch watch;
  try {
    for (size_t i = 0; i < frames.size(); ++i) {
      const auto r = tracker.Track(frames[i], masks[i] ? &*masks[i] : nullptr);
      estimate.push_back({frames[i].timestamp_s, r.T_world_camera});
      truth.push_back({frames[i].timestamp_s, frames[i].T_world_camera});
    }
  } catch (const std::exception& e) {
    out.error = e.what();
    return out;
  }
  out.seconds_per_frame = watch.Elapsed() / static_cast<double>(frames.size());
  if (const char* dir = std::getenv("SEMREC_BENCH_WRITE_POSES")) {
    io::WriteTumTrajectory(fs::path(dir) / "estimate.txt", estimate);
    io::WriteTumTrajectory(fs::path(dir) / "truth.txt", truth);
  }
  const eval::TrajectoryErrors e = eval::EvaluateTrajectory(estimate, truth);
  out.ate_m = e.ate_rmse_m;
  out.rpe_m = e.rpe_translation_rmse_m;
  out.lost = tracker.lost_frames();
  return out;
}

void Bench(const fs::path& sequence, const fs::path& masks_dir,
           size_t max_frames,
           const io::SequenceReaderOptions& reader_options = {}) {
  if (!fs::exists(sequence)) {
    std::printf("skipped %s: not found\n", sequence.string().c_str());
    return;
  }
  const io::SequenceReader reader =
      io::SequenceReader::Open(sequence, reader_options);
  std::vector<Frame> frames;
  std::vector<std::optional<LabelMap>> masks;
  size_t masked = 0;
  for (size_t i = 0; i < reader.size() && i < max_frames; ++i) {
    frames.push_back(reader.Read(i));
    fs::path m = masks_dir / fmt::format("{:06}.png", i);
    if (!fs::exists(m)) {
      m = masks_dir /
          (reader.index().frames[i].depth_path.stem().string() + ".png");
    }
    if (!masks_dir.empty() && fs::exists(m)) {
      masks.emplace_back(io::ReadLabelImage(m));
      ++masked;
    } else {
      masks.emplace_back();
    }
  }
  std::printf("%s: %zu frames, %zu with person maps\n",
              sequence.filename().string().c_str(), frames.size(), masked);
  std::printf("  %-32s %9s %9s %10s %6s %7s\n", "method", "ATE cm", "RPE cm",
              "ms/frame", "lost", "time x");
  double reference = 0.0;
  for (const Variant& v : Variants()) {
    for (const bool use_masks : {false, true}) {
      if (use_masks && masked == 0) continue;
      const Outcome o =
          Run(reader, frames,
              use_masks ? masks
                        : std::vector<std::optional<LabelMap>>(frames.size()),
              v.options);
      const std::string name = v.name + (use_masks ? " masked" : "");
      if (!o.error.empty()) {
        std::printf("  %-32s failed: %s\n", name.c_str(), o.error.c_str());
        continue;
      }
      if (reference == 0.0) reference = o.seconds_per_frame;
      std::printf("  %-32s %9.2f %9.2f %10.1f %6zu %7.2f\n", name.c_str(),
                  100 * o.ate_m, 100 * o.rpe_m, 1000 * o.seconds_per_frame,
                  o.lost, o.seconds_per_frame / reference);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (std::getenv("SEMREC_BENCH_DEBUG") != nullptr) {
    spdlog::set_level(spdlog::level::debug);
  }
  std::vector<std::string> positional;
  size_t max_frames = 1000000;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--frames" && i + 1 < argc) {
      max_frames = std::stoul(argv[++i]);
    } else if (a == "--keyframe-m" && i + 1 < argc) {
      g_keyframe_m = std::stod(argv[++i]);
    } else if (a == "--keyframe-deg" && i + 1 < argc) {
      g_keyframe_deg = std::stod(argv[++i]);
    } else if (a == "--depth-diff" && i + 1 < argc) {
      g_depth_diff_m = std::stod(argv[++i]);
    } else if (a == "--max-step" && i + 1 < argc) {
      g_max_step_m = std::stod(argv[++i]);
    } else if (a == "--only" && i + 1 < argc) {
      g_only = argv[++i];
    } else if (a == "--max-depth" && i + 1 < argc) {
      g_max_depth_m = std::stod(argv[++i]);
    } else if (a == "--downsampling" && i + 1 < argc) {
      g_downsampling = std::stoi(argv[++i]);
    } else {
      positional.push_back(a);
    }
  }
  try {
    if (!positional.empty()) {
      Bench(positional[0], positional.size() > 1 ? positional[1] : "",
            max_frames);
      return 0;
    }
    const fs::path data = bench::SampleDataDir();
    if (std::getenv("SEMREC_BENCH_SKIP_CHESS") == nullptr) {
      Bench(data / "7scenes_chess_0_99", "", max_frames);
    }
    // The dataset's rig-to-camera correction and calibration (README.md).
    io::SequenceReaderOptions bonn;
    bonn.pose_correction_path =
        fs::path(SEMREC_SOURCE_DIR) / "data/poses/bonn_rgbd_dynamic.yaml";
    bonn.intrinsics_path =
        fs::path(SEMREC_SOURCE_DIR) / "data/intrinsics/bonn_rgbd_dynamic.txt";
    const char* maps = std::getenv("SEMREC_BONN_PERSON_MAPS");
    Bench(data / "bonn_crowd_150", maps != nullptr ? maps : "", max_frames,
          bonn);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_odometry: %s\n", e.what());
    return 1;
  }
  return 0;
}
