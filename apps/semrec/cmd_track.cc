// `semrec track --detections det.txt --out result.txt`: tracking on
// MOTChallenge detections.
#include <cstdio>
#include <map>
#include <optional>

#include <fmt/format.h>

#include "commands.h"
#include "semrec/core/error.h"
#include "semrec/core/progress.h"
#include "semrec/io/mot_io.h"
#include "semrec/track/tracker.h"

namespace semrec::cli {
namespace {

struct TrackArgs {
  std::string detections;
  std::string out;
  std::string config = "improved";
  std::string cost;
  std::optional<int> max_lost;
  std::optional<bool> velocity;
  std::optional<double> min_score;
  std::optional<int> min_hits;
};

void RunTrack(const TrackArgs& args) {
  track::TrackerOptions options;
  if (args.config == "paper") {
    options = track::TrackerOptions::Paper();
  } else if (args.config == "improved") {
    options = track::TrackerOptions::Improved();
  } else {
    throw InvalidArgument("--config must be 'paper' or 'improved', got '" +
                          args.config + "'");
  }
  if (args.cost == "corners") {
    options.cost = track::TrackerOptions::Cost::kCorners;
  } else if (args.cost == "iou") {
    options.cost = track::TrackerOptions::Cost::kIou;
  } else if (!args.cost.empty()) {
    throw InvalidArgument("--cost must be 'corners' or 'iou', got '" +
                          args.cost + "'");
  }
  if (args.max_lost) options.max_lost_frames = *args.max_lost;
  if (args.velocity) options.constant_velocity = *args.velocity;
  if (args.min_score) options.min_score = *args.min_score;
  if (args.min_hits) options.min_hits = *args.min_hits;
  options.Check();
  const std::vector<io::MotBox> detections = io::ReadMotFile(args.detections);
  std::map<int, std::vector<track::Detection>> by_frame;
  for (const io::MotBox& b : detections) {
    by_frame[b.frame].push_back(
        {{b.left, b.top, b.width, b.height}, b.confidence});
  }
  const int frames = by_frame.empty() ? 0 : by_frame.rbegin()->first;
  track::Tracker tracker(options);
  std::vector<io::MotBox> result;
  Progress progress("tracking", frames);
  for (int f = 1; f <= frames; ++f) {
    const auto it = by_frame.find(f);
    const auto tracked = tracker.Update(
        it == by_frame.end() ? std::vector<track::Detection>{} : it->second);
    for (const auto& t : tracked) {
      if (!t.confirmed) continue;
      result.push_back({f, t.track_id, t.box.left, t.box.top, t.box.width,
                        t.box.height, t.score});
    }
    progress.Tick();
  }
  progress.Finish();
  io::WriteMotFile(args.out, result);
  std::printf("%s",
              fmt::format("{} frames, {} detections -> {} boxes; wrote {}\n",
                          frames, detections.size(), result.size(), args.out)
                  .c_str());
}

}  // namespace

void RegisterTrack(CLI::App& app) {
  auto args = std::make_shared<TrackArgs>();
  CLI::App* cmd = app.add_subcommand(
      "track",
      "Track people from MOTChallenge detections (Hungarian assignment between "
      "consecutive "
      "frames; the paper's cost is the sum of the four box-corner distances) "
      "and write a "
      "MOTChallenge result file. Evaluate it with 'semrec eval mot'.");
  cmd->add_option("--detections", args->detections, "MOTChallenge det.txt")
      ->required();
  cmd->add_option("--out,-o", args->out, "Result file (MOTChallenge format)")
      ->required();
  cmd->add_option(
         "--config", args->config,
         "paper (corner cost, no gate, previous frame only) or improved (IoU "
         "cost, "
         "constant velocity, lost tracks kept 10 frames, scores >= 0.7)")
      ->capture_default_str();
  cmd->add_option("--cost", args->cost, "Override the cost: corners or iou");
  cmd->add_option("--max-lost", args->max_lost,
                  "Override: frames a lost track stays matchable");
  cmd->add_option("--velocity", args->velocity,
                  "Override: constant-velocity prediction (true/false)");
  cmd->add_option("--min-score", args->min_score,
                  "Override: ignore detections below this score");
  cmd->add_option(
      "--min-hits", args->min_hits,
      "Override: report a track once it was seen in this many frames");
  cmd->callback([args] { RunTrack(*args); });
}

}  // namespace semrec::cli
