// The whole system in one streaming pass (the paper's pipeline): frames go in
// one at a time; each is segmented (semantic branch + masks + vote, every
// `segment_every`-th frame), its people are tracked (detector, box-prompted
// masks, re-identification; every frame), the static segments (people left
// out) are fused into objects and integrated into the objects' volumes, and
// the USD scene can be written at any time. Each frame is decoded once, each
// model runs once per frame it is needed for, and nothing goes through files.
//
// Labels may also come with the frames (ground truth, as the paper did on
// Hypersim): then no model runs.
#pragma once

#include <deque>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "semrec/core/frame.h"
#include "semrec/core/label_map.h"
#include "semrec/core/stopwatch.h"
#include "semrec/fuse/map_projection.h"
#include "semrec/fuse/segments.h"
#include "semrec/infer/model_registry.h"
#include "semrec/pipeline/map_guidance.h"
#include "semrec/pipeline/people_tracker.h"
#include "semrec/pipeline/scene_builder.h"
#include "semrec/segment/hybrid_segmenter.h"
#include "semrec/track/sequence.h"

namespace semrec::pipeline {

struct ScenePipelineOptions {
  enum class Labels {
    /// The hybrid segmenter and the people tracker run on the frames.
    kModels,
    /// Every frame brings its labels and person map (ground truth).
    kGiven,
  };
  Labels labels = Labels::kModels;
  /// Segment every n-th frame (1 = all); people are tracked on every frame.
  /// Fusion and volumes use the segmented frames only.
  int segment_every = 1;
  segment::HybridSegmenterOptions segmenter;
  /// Map guidance (models only): the map is projected into each frame to be
  /// segmented; masks are prompted only where it cannot explain the frame,
  /// and frames it explains almost wholly skip the segmentation models. Frame
  /// i sees the map after frame i - 2 (what the overlapped loop of
  /// RunSequence guarantees, so results do not depend on timing).
  bool map_guidance = false;
  MapGuidanceOptions guidance;
  fuse::MapProjectionOptions projection;
  /// Track people (models) or take the frames' person maps (given).
  bool track_people = true;
  PeopleTrackerOptions people;
  /// The offline step on finished tracks (gaps, short tracks) for tracks.txt
  /// and the people prims.
  track::OfflineOptions offline = track::OfflineOptions::Improved();
  SceneBuilderOptions scene;
  /// Draw overlays (classes with names, people with ids).
  bool overlays = true;
  void Check() const;
};

/// What the models gave for one frame: enough to redo the frame without them
/// (a resumed run replays these from its checkpoint).
struct ModelOutputs {
  /// The static labels (segmented frames only).
  std::optional<fuse::FrameLabels> labels;
  /// Detections with embeddings, as the tracker got them.
  std::vector<track::Detection> tracker_input;
  /// Tracked people's masks (track id per pixel; empty without people).
  LabelMap person_ids;
  /// Map guidance: how the frame was segmented ("full", "partial",
  /// "projection"; empty without guidance or labels).
  std::string guidance;
};

/// One frame and what comes with it.
struct PipelineInput {
  Frame frame;
  /// Name for per-frame outputs (overlays), e.g. the colour image's.
  std::string name;
  /// Labels::kGiven: the frame's static labels and person ids.
  std::optional<fuse::FrameLabels> labels;
  std::optional<LabelMap> person_ids;
  /// Labels::kModels: this frame's recorded model outputs; no model runs and
  /// no overlay is drawn (checkpoint replay).
  std::optional<ModelOutputs> replay;
};

/// Seconds spent per stage, summed over frames.
struct StageSeconds {
  /// Reading and decoding the frame (filled in by whoever reads them).
  double read = 0.0;
  double segment = 0.0;
  double track = 0.0;
  double fuse = 0.0;
  double volumes = 0.0;
  double overlay = 0.0;
  double write = 0.0;
  double Total() const {
    return read + segment + track + fuse + volumes + overlay + write;
  }
};

/// Map guidance over the frames so far.
struct GuidanceCounts {
  /// Segmented frames by how they were segmented.
  size_t full = 0;
  size_t partial = 0;
  size_t projection = 0;
  /// Of the partial frames, those made partial only by the semantic branch
  /// disagreeing with the map (MapGuidanceOptions::prompt_on_disagreement).
  size_t disagreement = 0;
  /// Of the frames this process segmented (not replayed): encoder calls and
  /// prompts decoded.
  size_t encoder_calls = 0;
  size_t prompts_decoded = 0;
  /// Summed over guided (partial and projection) frames: the share of valid
  /// depth the map did not explain.
  double unexplained_share_sum = 0.0;
};

/// The object detector's evidence over the frames this process segmented.
struct ObjectDetectionCounts {
  /// Detections of mapped classes used, and what they did (HybridResult).
  size_t detections = 0;
  size_t matched = 0;
  size_t added = 0;
  size_t parts = 0;
  /// Masks joined into their detected object's instance.
  size_t parts_joined = 0;
  /// Frames whose one detector pass served both people tracking and the
  /// object evidence.
  size_t shared_passes = 0;
};

/// What one frame gave.
struct PipelineFrameResult {
  bool segmented = false;
  size_t segments = 0;
  size_t people = 0;
  /// The overlay (empty unless options.overlays; none on replay).
  ColorImage overlay;
  /// Labels::kModels: what the models gave (for the checkpoint).
  ModelOutputs outputs;
};

/// A frame after the models (segmentation, people), before fusion.
struct PreparedFrame {
  Frame frame;
  /// Its place in the stream (Prepare() calls before it).
  size_t position = 0;
  bool replay = false;
  std::optional<fuse::FrameLabels> labels;
  std::vector<PersonObservation> people;
  std::optional<LabelMap> person_ids;
  std::vector<track::Detection> tracker_input;
  /// Map guidance: the frame's mode (ModelOutputs::guidance) and, for the
  /// overlay, the decision (with the prompt region).
  std::string guidance;
  std::optional<GuidanceDecision> decision;
};

class ScenePipeline {
 public:
  /// `registry`: the models (Labels::kModels; may be null for kGiven).
  /// `given_classes`: the label set of given labels (Labels::kGiven).
  /// Models load here; throws as OnnxModel does when one is missing.
  ScenePipeline(const infer::ModelRegistry* registry,
                const LabelSet* given_classes,
                const ScenePipelineOptions& options);
  ~ScenePipeline();

  /// Runs every stage on one frame. Frames must come in order.
  PipelineFrameResult Process(const PipelineInput& input);

  /// Process() in two steps that may overlap across frames: Prepare() runs
  /// the models (segmentation, people tracking) and Integrate() fuses and
  /// integrates the result. Prepare(frame i + 1) may run on one thread while
  /// Integrate(frame i) runs on another; each of the two must be called in
  /// frame order, one call at a time.
  PreparedFrame Prepare(PipelineInput input);
  PipelineFrameResult Integrate(PreparedFrame prepared);

  /// Ends the stream (fusion's end-of-sequence clean-up, the offline track
  /// step); then Write() gives the final scene.
  void Finish();

  /// Writes the scene (USD, PLY) to `out_dir`; mid-stream, a snapshot.
  SceneWriteResult Write(const std::filesystem::path& out_dir,
                         const SceneWriteOptions& write_options);

  /// The meshes Write() would write (SceneBuilder::Meshes), without files.
  std::vector<usd::MeshPrim> Meshes(SceneWriteResult* result = nullptr);

  /// People boxes (MOTChallenge; frame = frame index + 1): after Finish() the
  /// offline-smoothed tracks, before it the online ones.
  std::vector<io::MotBox> Tracks() const;

  const LabelSet& classes() const { return builder_->classes(); }
  const SceneBuilder& scene() const { return *builder_; }
  /// Wall time per stage, and the CPU time of the thread that ran it (ONNX
  /// Runtime's worker threads not included: see the process CPU time).
  const StageSeconds& seconds() const { return seconds_; }
  const StageSeconds& cpu_seconds() const { return cpu_seconds_; }
  /// Frames prepared, and segmented frames integrated.
  size_t frames() const { return frames_; }
  size_t segmented_frames() const { return segmented_frames_; }
  const GuidanceCounts& guidance_counts() const { return guidance_counts_; }
  const ObjectDetectionCounts& object_counts() const { return object_counts_; }
  const ScenePipelineOptions& options() const { return options_; }

 private:
  /// The models' labels for a frame (with map guidance when on); sets `mode`.
  fuse::FrameLabels SegmentFrame(
      const Frame& frame, size_t position,
      const std::optional<LabelMap>& person_ids, std::string* mode,
      std::optional<GuidanceDecision>* decision,
      const std::vector<detect::LabeledDetection>* detections);
  /// Map guidance bookkeeping for a segmented frame's mode.
  void CountGuidance(const std::string& mode, const Transform& T_world_camera);
  /// The map frame `position` is guided by (after frame position - 2).
  std::shared_ptr<const std::vector<fuse::SceneSegment>> MapFor(
      size_t position);
  void PublishMap(size_t position, const fuse::FrameLabels& labels);

  ScenePipelineOptions options_;
  std::unique_ptr<segment::HybridSegmenter> segmenter_;
  std::unique_ptr<PeopleTracker> tracker_;
  // One detector pass per frame for people and object evidence, when both
  // use the same detector (null otherwise: each runs its own).
  std::unique_ptr<detect::YoloxDetector> shared_detector_;
  std::unique_ptr<SceneBuilder> builder_;
  std::vector<track::TrackPoint> track_points_;
  std::vector<track::TrackPoint> finished_tracks_;
  bool finished_ = false;
  void AddLap(const StageWatch::Lap& lap, double StageSeconds::*stage) {
    seconds_.*stage += lap.wall;
    cpu_seconds_.*stage += lap.cpu;
  }

  StageSeconds seconds_;
  StageSeconds cpu_seconds_;
  size_t frames_ = 0;
  size_t segmented_frames_ = 0;
  // Map guidance: Prepare() side.
  GuidanceCounts guidance_counts_;
  ObjectDetectionCounts object_counts_;
  std::optional<Transform> T_world_last_full_;
  size_t frames_since_full_ = 0;
  // Maps published by Integrate() (tagged with the frame's position) for
  // Prepare() on another thread.
  std::mutex maps_mutex_;
  std::deque<
      std::pair<size_t, std::shared_ptr<const std::vector<fuse::SceneSegment>>>>
      maps_;
};

/// The people in a person id map as boxes (one per id, tight around its
/// pixels) with their masks: what the tracker would report.
std::vector<PersonObservation> PeopleFromIdMap(const LabelMap& person_ids);

}  // namespace semrec::pipeline
