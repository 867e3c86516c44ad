// `semrec run`: a recording through the whole pipeline (ScenePipeline) in one
// pass, with the outputs a user looks at: the USD scene (+ PLY per object),
// tracks.txt (MOTChallenge), overlay/ PNGs, report.json (per-stage time,
// frames/s, peak memory, objects per class, people, skipped frames, versions
// and model checksums), snapshots of the scene while it runs, and checkpoints
// to resume an interrupted run.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "semrec/core/progress.h"
#include "semrec/fuse/segments.h"
#include "semrec/infer/model_registry.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/odometry/pose_tracker.h"
#include "semrec/pipeline/run_report.h"
#include "semrec/pipeline/scene_pipeline.h"

namespace semrec::pipeline {

struct RunOptions {
  ScenePipelineOptions pipeline;
  /// Where the camera poses come from: the recording's pose file (kFile),
  /// estimated from the frames in the same pass (kEstimate: odometry/,
  /// tracked people left out), or the recording's when it has them, else
  /// estimated (kAuto). Estimated poses are written to poses.txt (TUM).
  enum class Poses { kFile, kEstimate, kAuto };
  Poses poses = Poses::kAuto;
  odometry::PoseTrackerOptions odometry;
  /// Estimated poses: pixels of these classes (names of the run's label
  /// set) are left out of tracking on the frames that are segmented, as the
  /// tracked people's are on every frame.
  std::vector<std::string> dynamic_classes;
  /// Labels::kGiven: where the labels come from (fuse::LabelSpec; default
  /// "gt", the sequence's own layers) and the people spec of
  /// PersonMapSource ("gt"; "" = the person layer when the sequence has one).
  fuse::LabelSpec given_labels;
  std::string given_people;
  /// Write the scene every n frames while running (0 = only at the end).
  int snapshot_every = 0;
  /// Write a checkpoint every n frames (0 = only at the end); --resume
  /// continues from the last one.
  int checkpoint_every = 25;
  /// Continue an interrupted run in the same output folder.
  bool resume = false;
  /// Read and decode the next frame on another thread while this one is
  /// processed (off: one after the other; for measurements).
  bool prefetch = true;
  /// Fuse and integrate frame i on another thread while the models work on
  /// frame i + 1 (off: one after the other; for measurements).
  bool overlap = true;
  /// Stop at the first corrupt or missing frame instead of skipping it.
  bool strict = false;
  bool write_ply = true;
  bool usdz = false;
  /// Also write scene.glb (glTF 2.0 binary).
  bool glb = false;
  /// Write into a non-empty output folder (a fresh run).
  bool overwrite = false;
  /// The effective configuration as text (YAML): written to run.yaml, into
  /// the USD layer metadata, and compared on --resume.
  std::string config_text;
  /// What a checkpoint must match to be resumed: the options that change the
  /// scene (empty: config_text).
  std::string resume_key;
  void Check() const;
};

const char* PosesName(RunOptions::Poses poses);
RunOptions::Poses ParsePoses(const std::string& text);
/// Whether a run with `poses` estimates them for a recording that has
/// (or lacks) its own; a recording without them opens only when
/// `poses` is not kFile (io::SequenceReaderOptions::require_poses).
bool EstimatesPoses(RunOptions::Poses poses, bool recording_has_poses);

struct RunResult {
  size_t frames = 0;
  size_t skipped_frames = 0;
  size_t resumed_frames = 0;
  SceneWriteResult scene;
  size_t tracks = 0;
  double seconds = 0.0;
  /// Everything report.json holds.
  RunReport report;
};

/// Runs `reader`'s frames through the pipeline into `out_dir`. Corrupt or
/// missing frames are skipped with a warning naming the file (counted in the
/// report) unless `strict`. Throws on bad options, missing models, an
/// unusable output folder, or a checkpoint that does not match.
RunResult RunSequence(const io::SequenceReader& reader,
                      const infer::ModelRegistry* registry,
                      const RunOptions& options,
                      const std::filesystem::path& out_dir,
                      const ProgressOptions& progress = {});

/// The terminal summary of a run: frames, time per stage, objects per
/// class, people, where the outputs are.
std::string RunSummaryTable(const RunResult& result,
                            const std::filesystem::path& out_dir);

/// Peak resident memory of this process so far (bytes; 0 if unknown).
size_t PeakRssBytes();

}  // namespace semrec::pipeline
