// Tracking benchmark: association cost per frame (the figure: 50
// detections, association only) for each tracker configuration, as
// microseconds and as a ratio to the paper's configuration run in the same
// process; then MOTA / IDF1 / ID switches of every configuration on
// TUD-Campus public detections when ../shared/data is there.
//   bench_track [detections_per_frame=50] [frames=2000]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "semrec/core/random.h"
#include "semrec/core/sample_data.h"
#include "semrec/core/stopwatch.h"
#include "semrec/eval/mot.h"
#include "semrec/io/mot_io.h"
#include "semrec/track/sequence.h"
#include "semrec/track/tracker.h"

namespace fs = std::filesystem;
using namespace semrec;

namespace {

struct Config {
  std::string name;
  track::TrackerOptions options;
  bool embeddings = false;
  /// Offline steps on the finished tracks (TUD-Campus only).
  track::OfflineOptions offline = {};
};

std::vector<Config> Configs() {
  std::vector<Config> configs;
  configs.push_back(
      {"paper (corners, no gate)", track::TrackerOptions::Paper()});
  track::TrackerOptions gated;
  configs.push_back({"corners + gate 200 px", gated});
  track::TrackerOptions iou = track::TrackerOptions::Paper();
  iou.cost = track::TrackerOptions::Cost::kIou;
  configs.push_back({"iou", iou});
  track::TrackerOptions velocity = track::TrackerOptions::Improved();
  velocity.motion = track::TrackerOptions::Motion::kVelocity;
  configs.push_back({"improved, velocity", velocity});
  configs.push_back({"improved (kalman)", track::TrackerOptions::Improved()});
  configs.push_back(
      {"improved + re-ID (256-d)", track::TrackerOptions::Improved(), true});
  track::OfflineOptions gaps;
  gaps.max_gap_frames = 10;
  configs.push_back({"improved + gap filling",
                     track::TrackerOptions::Improved(), false, gaps});
  configs.push_back({"improved + offline steps",
                     track::TrackerOptions::Improved(), false,
                     track::OfflineOptions::Improved()});
  return configs;
}

// People walking with constant velocity, detection noise and 5% misses; each
// one has a fixed 256-d appearance embedding plus noise.
std::vector<std::vector<track::Detection>> Walkers(int people, int frames) {
  Rng rng(11);
  struct Walker {
    double x, y, vx, vy, w, h;
    std::vector<float> look;
  };
  std::vector<Walker> walkers(people);
  for (Walker& p : walkers) {
    p = {rng.Uniform(0, 1920),
         rng.Uniform(0, 1080),
         rng.Uniform(-4, 4),
         rng.Uniform(-2, 2),
         rng.Uniform(30, 60),
         rng.Uniform(80, 160),
         {}};
    p.look.resize(256);
    for (float& v : p.look) v = static_cast<float>(rng.Normal());
  }
  std::vector<std::vector<track::Detection>> out(frames);
  for (int f = 0; f < frames; ++f) {
    for (Walker& p : walkers) {
      p.x += p.vx;
      p.y += p.vy;
      // Bounce inside the frame so the count stays constant.
      if (p.x < 0 || p.x > 1920) p.vx = -p.vx;
      if (p.y < 0 || p.y > 1080) p.vy = -p.vy;
      if (rng.Uniform() < 0.05) continue;
      track::Detection d;
      d.box = {p.x + 2 * rng.Normal(), p.y + 2 * rng.Normal(), p.w, p.h};
      d.score = rng.Uniform(0.7, 1.0);
      d.embedding = p.look;
      for (float& v : d.embedding) v += static_cast<float>(0.1 * rng.Normal());
      out[f].push_back(std::move(d));
    }
  }
  return out;
}

std::vector<io::MotBox> Run(
    const Config& config,
    const std::map<int, std::vector<track::Detection>>& by_frame, int frames) {
  track::Tracker tracker(config.options);
  return track::ToMotBoxes(track::FinishTracks(
      track::TrackSequence(&tracker, by_frame, frames), config.offline));
}

}  // namespace

int main(int argc, char** argv) {
  const int people = argc > 1 ? std::atoi(argv[1]) : 50;
  const int frames = argc > 2 ? std::atoi(argv[2]) : 2000;
  if (people <= 0 || frames <= 0) {
    std::fprintf(stderr,
                 "usage: bench_track [detections_per_frame] [frames]\n");
    return 2;
  }
  const auto walkers = Walkers(people, frames);
  std::printf(
      "Association cost, %d walkers (~%d detections/frame), %d frames\n",
      people, static_cast<int>(std::lround(people * 0.95)), frames);
  std::printf("%-28s %12s %10s %8s\n", "configuration", "us/frame", "vs paper",
              "tracks");
  double reference_us = 0;
  for (const Config& config : Configs()) {
    if (!config.offline.Off()) continue;  // same association as without
    track::Tracker tracker(config.options);
    std::vector<std::vector<track::Detection>> input = walkers;
    if (!config.embeddings) {
      for (auto& frame : input)
        for (auto& d : frame) d.embedding.clear();
    }
    int max_id = 0;
    const Stopwatch start;
    for (const auto& frame : input) {
      for (const auto& t : tracker.Update(frame))
        max_id = std::max(max_id, t.track_id);
    }
    const double us = 1e6 * start.Elapsed() / frames;
    if (reference_us == 0) reference_us = us;
    std::printf("%-28s %12.1f %9.2fx %8d\n", config.name.c_str(), us,
                us / reference_us, max_id);
  }

  const fs::path tud =
      semrec::SampleDataDir().value_or("../shared/data") / "mot15_tud_campus";
  if (!fs::exists(tud / "det/det.txt")) {
    std::printf("\nTUD-Campus not found at %s: skipped\n", tud.c_str());
    return 0;
  }
  const auto gt = io::ReadMotFile(tud / "gt/gt.txt");
  const auto by_frame =
      track::DetectionsByFrame(io::ReadMotFile(tud / "det/det.txt"));
  const int last = by_frame.empty() ? 0 : by_frame.rbegin()->first;
  std::printf("\nTUD-Campus public detections (%s)\n", tud.c_str());
  std::printf("%-28s %7s %7s %7s %5s %5s %5s\n", "configuration", "MOTA",
              "IDF1", "HOTA", "FP", "FN", "IDsw");
  for (const Config& config : Configs()) {
    if (config.embeddings) continue;
    const eval::MotMetrics m =
        eval::EvaluateMot(gt, Run(config, by_frame, last));
    std::printf("%-28s %7.4f %7.4f %7.4f %5zu %5zu %5zu\n", config.name.c_str(),
                m.mota, m.idf1, m.hota, m.false_positives, m.false_negatives,
                m.id_switches);
  }
  std::printf("(SORT on these detections: MOTA 0.627, from the issue)\n");
  return 0;
}
