#include "semrec/pipeline/run_sequence.h"

#include <sys/resource.h>

#include <exception>
#include <fstream>
#include <future>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <tbb/task_group.h>

#include "semrec/core/enum_names.h"
#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/core/sha256.h"
#include "semrec/core/stopwatch.h"
#include "semrec/fuse/fuse_sequence.h"
#include "semrec/infer/onnx_model.h"
#include "semrec/io/image_io.h"
#include "semrec/io/mot_io.h"
#include "semrec/io/pose_io.h"
#include "semrec/pipeline/checkpoint.h"
#include "semrec/pipeline/people_3d.h"
#include "semrec/pipeline/run_report.h"

namespace fs = std::filesystem;

namespace semrec::pipeline {
namespace {

// YAML lines as "key: value; key: value" (comments left out): USD layer
// metadata strings hold one line.
std::string OneLine(const std::string& text) {
  std::string out;
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(start, end - start);
    if (!line.empty() && line[0] != '#') {
      out += (out.empty() ? "" : "; ") + line;
    }
    start = end + 1;
  }
  return out;
}

std::string StageDetail(const StageSeconds& s, size_t frames) {
  if (frames == 0) return "";
  const double n = static_cast<double>(frames);
  return fmt::format(
      "per frame: segment {:.2f}s track {:.2f}s fuse {:.0f}ms "
      "volumes {:.0f}ms",
      s.segment / n, s.track / n, 1000 * s.fuse / n, 1000 * s.volumes / n);
}

// Registry entries of the models a run uses, with their checksums.
std::vector<ModelRecord> ModelRecords(const infer::ModelRegistry* registry,
                                      const ScenePipelineOptions& options) {
  std::vector<ModelRecord> out;
  if (registry == nullptr ||
      options.labels != ScenePipelineOptions::Labels::kModels) {
    return out;
  }
  std::vector<std::string> names = {options.segmenter.semantic.model};
  if (options.segmenter.use_masks) {
    names.push_back(options.segmenter.masks.model.encoder);
    names.push_back(options.segmenter.masks.model.decoder);
  }
  if (options.segmenter.objects.enabled()) {
    names.push_back(options.segmenter.objects.model);
  }
  if (options.track_people) {
    names.push_back(options.people.detector.model);
    if (options.people.masks) {
      names.push_back(options.people.mask_model.encoder);
      names.push_back(options.people.mask_model.decoder);
    }
  }
  std::set<std::string> seen;
  for (const std::string& name : names) {
    if (!seen.insert(name).second || !registry->Contains(name)) continue;
    const infer::ModelEntry& e = registry->Get(name);
    // Models made at setup (TFLite conversions) have no registered checksum:
    // the report gives the installed file's.
    std::string sha256 = e.sha256;
    const fs::path file =
        infer::ModelFile(e, options.segmenter.semantic.runtime);
    if (sha256.empty() && fs::is_regular_file(file)) {
      sha256 = Sha256File(file);
    }
    out.push_back({name, file.string(), sha256, !e.sha256.empty()});
  }
  return out;
}

}  // namespace

const char* PosesName(RunOptions::Poses poses) {
  switch (poses) {
    case RunOptions::Poses::kFile:
      return "file";
    case RunOptions::Poses::kEstimate:
      return "estimate";
    case RunOptions::Poses::kAuto:
      return "auto";
  }
  return "?";
}

bool EstimatesPoses(RunOptions::Poses poses, bool recording_has_poses) {
  return poses == RunOptions::Poses::kEstimate ||
         (poses == RunOptions::Poses::kAuto && !recording_has_poses);
}

RunOptions::Poses ParsePoses(const std::string& text) {
  return ParseEnumName(text,
                       {RunOptions::Poses::kFile, RunOptions::Poses::kEstimate,
                        RunOptions::Poses::kAuto},
                       PosesName, "--poses");
}

void RunOptions::Check() const {
  pipeline.Check();
  odometry.Check();
  CheckArgument(snapshot_every >= 0, "run: snapshot_every must be >= 0");
  CheckArgument(checkpoint_every >= 0, "run: checkpoint_every must be >= 0");
  CheckArgument(!(resume && overwrite),
                "run: --resume continues the run in the output folder; "
                "--overwrite would start afresh: give one of them");
}

size_t PeakRssBytes() {
  // VmHWM belongs to this process image (getrusage's maximum is carried over
  // from the parent through fork and exec).
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmHWM:", 0) == 0) {
      return static_cast<size_t>(std::stoull(line.substr(6))) * 1024;  // kB
    }
  }
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return 0;
  return static_cast<size_t>(usage.ru_maxrss) * 1024;  // Linux: kilobytes
}

// Where the main thread's time went, and what the other threads did: reading
// runs ahead on a prefetch thread, fusion, volumes, overlays and checkpoints
// of frame i on an integration thread while frame i + 1 is segmented.
struct RunTiming {
  double setup = 0.0, wait_frames = 0.0, prepare = 0.0, wait_integration = 0.0,
         finish = 0.0;
  double read_cpu = 0.0;
  double integrate_wall = 0.0, integrate_cpu = 0.0;
  double main_cpu_start = ThreadCpuSeconds();
  double process_cpu_start = ProcessCpuSeconds();
};

nlohmann::json TimingJson(const RunTiming& t, const StageSeconds& wall,
                          const StageSeconds& cpu, double run_seconds) {
  const auto stage = [](double w, double c) {
    return nlohmann::json{{"wall", w}, {"cpu", c}};
  };
  const double accounted =
      t.setup + t.wait_frames + t.prepare + t.wait_integration + t.finish;
  return {
      {"run_wall", run_seconds},
      {"process_cpu", ProcessCpuSeconds() - t.process_cpu_start},
      {"main_thread",
       {{"setup", t.setup},
        {"waiting_for_frames", t.wait_frames},
        {"segment_and_track", t.prepare},
        {"waiting_for_integration", t.wait_integration},
        {"finish_and_write", t.finish},
        {"other", run_seconds - accounted},
        {"cpu", ThreadCpuSeconds() - t.main_cpu_start}}},
      {"read_thread", stage(wall.read, t.read_cpu)},
      {"integration_thread", stage(t.integrate_wall, t.integrate_cpu)},
      {"stages",
       {{"read", stage(wall.read, t.read_cpu)},
        {"segment", stage(wall.segment, cpu.segment)},
        {"track", stage(wall.track, cpu.track)},
        {"fuse", stage(wall.fuse, cpu.fuse)},
        {"volumes", stage(wall.volumes, cpu.volumes)},
        {"overlay", stage(wall.overlay, cpu.overlay)},
        {"write", stage(wall.write, cpu.write)}}},
      {"note",
       "main_thread's parts add up to run_wall. read runs on its own thread "
       "ahead of the main thread (waiting_for_frames is what it cost); fuse "
       "and volumes run on the integration thread while the next frame is "
       "segmented, so their wall time overlaps segment's "
       "(waiting_for_integration is what they cost the run), and each "
       "frame's overlay is drawn beside its fuse and volumes (on a worker "
       "thread: its wall time overlaps theirs). cpu is the "
       "running thread's CPU time: ONNX Runtime's worker threads are in "
       "process_cpu only; wall well above cpu means the stage waited for the "
       "cores."}};
}

namespace {

// One frame read and decoded (on the prefetch thread), or why it could not be.
struct Loaded {
  PipelineInput input;
  std::exception_ptr error;
  double seconds = 0.0, cpu = 0.0;
};

// RunSequence's state: frames are read ahead on a prefetch thread, segmented
// and tracked on this one, and fused and integrated (with their overlay and
// checkpoint) on an integration thread while the next frame is segmented;
// each side keeps frame order.
class SequenceRun {
 public:
  SequenceRun(const io::SequenceReader& reader,
              const infer::ModelRegistry* registry, const RunOptions& options,
              const fs::path& out_dir, const ProgressOptions& progress_options)
      : reader_(reader),
        registry_(registry),
        options_(options),
        out_dir_(out_dir),
        models_(options.pipeline.labels ==
                ScenePipelineOptions::Labels::kModels) {
    PrepareOutput();
    OpenGivenLabels();
    pipeline_.emplace(registry, source_ ? &source_->classes() : nullptr,
                      options.pipeline);
    StartPoseTracking();
    begin_ = StartOrResume();
    WriteTextFileAtomic(out_dir_ / "run.yaml", options_.config_text);
    write_ = SceneWriteOptions::For(reader, options.write_ply, options.usdz);
    write_.custom_layer_data["config"] = OneLine(options.config_text);
    snapshot_ = write_;
    snapshot_.write_ply = false;
    snapshot_.usdz = false;
    write_.glb = options.glb;
    snapshot_.glb = false;
    progress_.emplace("run", reader.size(), progress_options);
  }

  RunResult Run() {
    timing_.setup = run_time_.Elapsed();
    StartLoading(0);
    for (size_t i = 0; i < reader_.size(); ++i) ProcessFrame(i);
    WaitIntegrating();
    progress_->Finish();
    return Finish();
  }

 private:
  void PrepareOutput() {
    if (!options_.resume) RequireEmptyOrOverwrite(out_dir_, options_.overwrite);
    std::error_code ec;
    fs::create_directories(out_dir_, ec);
    if (ec) {
      throw IoError(out_dir_, "cannot create output folder: " + ec.message());
    }
  }

  // Given labels: the sequence's own layers (or a label folder).
  void OpenGivenLabels() {
    if (models_) return;
    source_ = fuse::SegmentationSource::Create(options_.given_labels, reader_);
    if (!options_.pipeline.track_people) return;
    std::string people = options_.given_people;
    if (people.empty() &&
        reader_.index().frames.front().layers.contains("person")) {
      people = "gt";
    }
    if (!people.empty()) person_maps_.emplace(people, reader_);
  }

  // The first frame to process: 0, or after the checkpoint's last frame.
  size_t StartOrResume() {
    Sha256 config_hash;
    config_hash.Update(options_.resume_key.empty() ? options_.config_text
                                                   : options_.resume_key);
    const RunIdentity identity = {reader_.root().string(), reader_.layout(),
                                  reader_.size(), config_hash.HexDigest()};
    if (!options_.resume) {
      store_.Start(identity);
      return 0;
    }
    const size_t begin = store_.Resume(identity);
    spdlog::info(
        "resuming: {} of {} frames are done; replaying them without "
        "the models",
        begin, reader_.size());
    return begin;
  }

  // Poses from the frames: asked for, or (auto) the recording has none.
  void StartPoseTracking() {
    using Poses = RunOptions::Poses;
    const bool has_poses = reader_.index().has_poses;
    if (options_.poses == Poses::kFile && !has_poses) {
      throw InvalidArgument(
          reader_.root().string() +
          ": the recording has no camera poses and --poses file was given: "
          "use --poses estimate (or auto)");
    }
    poses_.file = reader_.index().pose_source;
    if (!EstimatesPoses(options_.poses, has_poses)) return;
    if (options_.pipeline.map_guidance) {
      throw InvalidArgument(
          "map guidance projects the map at each frame's pose before it is "
          "segmented, and estimated poses come after: leave out "
          "--map-guidance, or give the recording's poses (--poses file)");
    }
    for (const std::string& name : options_.dynamic_classes) {
      const auto id = pipeline_->classes().FindByName(name);
      if (!id) {
        throw InvalidArgument(
            "--dynamic-classes: the label set has no class '" + name + "'");
      }
      dynamic_ids_.insert(*id);
    }
    tracker_.emplace(options_.odometry, reader_.intrinsics());
    poses_.source = "estimated";
    poses_.file = "poses.txt";
    poses_.method = fmt::format("{}, {} loss",
                                odometry::MethodName(options_.odometry.method),
                                odometry::LossName(options_.odometry.loss));
    spdlog::info("{}: camera poses estimated from the frames ({})",
                 reader_.root().string(), poses_.method);
  }

  // The frame's pose from the tracker, with its tracked people left out.
  void EstimatePose(PreparedFrame* prepared) {
    const Stopwatch watch;
    const LabelMap* masked =
        prepared->person_ids ? &*prepared->person_ids : nullptr;
    // Dynamic classes where the frame was segmented, beside the people.
    std::optional<LabelMap> with_dynamic;
    if (!dynamic_ids_.empty() && prepared->labels) {
      const LabelMap& semantic = prepared->labels->semantic;
      with_dynamic = masked != nullptr
                         ? *masked
                         : LabelMap(semantic.width(), semantic.height());
      for (size_t p = 0; p < semantic.NumPixels(); ++p) {
        if (dynamic_ids_.contains(semantic.data()[p])) {
          with_dynamic->data()[p] = 1;
        }
      }
      masked = &*with_dynamic;
    }
    const odometry::PoseTrackResult r =
        tracker_->Track(prepared->frame, masked);
    prepared->frame.T_world_camera = r.T_world_camera;
    estimated_.push_back({prepared->frame.timestamp_s, r.T_world_camera});
    poses_.frames.push_back({prepared->frame.index, r.tracked, r.keyframe,
                             r.fitness, r.inlier_rmse_m, r.masked_pixels,
                             r.lost_reason});
    if (!r.tracked) {
      spdlog::warn("frame {}: camera not tracked ({}); it keeps the last pose",
                   prepared->frame.index, r.lost_reason);
    }
    poses_.seconds += watch.Elapsed();
  }

  Loaded Load(size_t i) {
    Loaded loaded;
    const Stopwatch read_time;
    const double read_cpu = ThreadCpuSeconds();
    loaded.input.name =
        reader_.index().frames[i].color_path.stem().string() + ".png";
    try {
      loaded.input.frame = reader_.Read(i);
      if (!models_) {
        loaded.input.labels = source_->Get(reader_, i);
        if (person_maps_) loaded.input.person_ids = person_maps_->Get(i);
      }
    } catch (...) {
      loaded.error = std::current_exception();
    }
    loaded.seconds = read_time.Elapsed();
    loaded.cpu = ThreadCpuSeconds() - read_cpu;
    return loaded;
  }

  // Reading and decoding frame i + 1 overlaps the work on frame i.
  void StartLoading(size_t i) {
    if (i >= reader_.size()) return;
    next_ = std::async(
        options_.prefetch ? std::launch::async : std::launch::deferred,
        [this, i] { return Load(i); });
  }

  void WaitIntegrating() {
    const Stopwatch wait;
    if (integrating_.valid()) integrating_.get();
    timing_.wait_integration += wait.Elapsed();
    if (tick_pending_) {
      progress_->set_detail(
          StageDetail(pipeline_->seconds(), pipeline_->frames()));
      progress_->Tick();
      tick_pending_ = false;
    }
  }

  void Skip(size_t i, const std::string& reason) {
    skipped_.push_back({i, reason});
    progress_->Tick();
  }

  void ProcessFrame(size_t i) {
    const Stopwatch wait_frame;
    Loaded loaded = next_.get();
    timing_.wait_frames += wait_frame.Elapsed();
    StartLoading(i + 1);
    PipelineInput& input = loaded.input;
    const bool replay = i < begin_;
    std::optional<CheckpointFrame> saved;
    if (replay) {
      saved = store_.Load(i);
      if (saved->skipped) {
        WaitIntegrating();
        Skip(i, *saved->skipped);
        return;
      }
    }
    read_seconds_ += loaded.seconds;
    timing_.read_cpu += loaded.cpu;
    if (loaded.error) {
      WaitIntegrating();
      try {
        std::rethrow_exception(loaded.error);
      } catch (const FileError& e) {
        if (options_.strict || replay) throw;
        spdlog::warn("skipping frame {}: {}", i, e.what());
        store_.Record(i, {std::string(e.what()), std::nullopt});
        Skip(i, e.what());
        return;
      }
    }
    if (replay && models_) input.replay = std::move(saved->outputs);
    std::string name = input.name;
    const Stopwatch prepare;
    PreparedFrame prepared = pipeline_->Prepare(std::move(input));
    if (tracker_) EstimatePose(&prepared);
    timing_.prepare += prepare.Elapsed();
    WaitIntegrating();
    integrating_ = std::async(
        options_.overlap ? std::launch::async : std::launch::deferred,
        [this, i, replay, name = std::move(name),
         prepared = std::move(prepared)]() mutable {
          StageWatch watch;
          Integrate(i, replay, name, std::move(prepared));
          const StageWatch::Lap lap = watch.Next();
          timing_.integrate_wall += lap.wall;
          timing_.integrate_cpu += lap.cpu;
        });
    tick_pending_ = true;
  }

  // On the integration thread: fusion and volumes, then the overlay's PNG and
  // the checkpoint's side by side, commits and snapshots.
  void Integrate(size_t i, bool replay, const std::string& name,
                 PreparedFrame prepared) {
    const PipelineFrameResult frame = pipeline_->Integrate(std::move(prepared));
    if (replay) {
      ++resumed_frames_;
      return;
    }
    tbb::task_group files;
    if (!frame.overlay.empty()) {
      files.run(
          [&] { io::WritePng(out_dir_ / "overlay" / name, frame.overlay); });
    }
    store_.Record(
        i, {std::nullopt, models_ ? std::optional<ModelOutputs>(frame.outputs)
                                  : std::nullopt});
    files.wait();
    if (options_.checkpoint_every > 0 &&
        (i + 1) % options_.checkpoint_every == 0) {
      store_.Commit(i + 1);
    }
    if (options_.snapshot_every > 0 && (i + 1) % options_.snapshot_every == 0 &&
        i + 1 < reader_.size()) {
      pipeline_->Write(out_dir_, snapshot_);
      ++snapshots_;
    }
  }

  RunResult Finish() {
    const Stopwatch finish;
    store_.Commit(reader_.size());
    pipeline_->Finish();
    RunResult result;
    result.resumed_frames = resumed_frames_;
    result.scene = pipeline_->Write(out_dir_, write_);
    const std::vector<io::MotBox> tracks = pipeline_->Tracks();
    io::WriteMotFile(out_dir_ / "tracks.txt", tracks);
    if (tracker_) {
      io::WriteTumTrajectory(out_dir_ / "poses.txt", estimated_);
      poses_.keyframes = tracker_->keyframes();
      poses_.lost_frames = tracker_->lost_frames();
    }
    std::set<int> track_ids;
    for (const io::MotBox& b : tracks) track_ids.insert(b.id);
    result.tracks = track_ids.size();
    result.frames = reader_.size();
    result.skipped_frames = skipped_.size();
    timing_.finish = finish.Elapsed();
    result.seconds = run_time_.Elapsed();
    result.report = MakeReport(result);
    WriteRunReport(out_dir_ / "report.json", result.report);
    return result;
  }

  RunReport MakeReport(const RunResult& result) const {
    StageSeconds s = pipeline_->seconds();
    s.read = read_seconds_;
    const double processed = static_cast<double>(pipeline_->frames());
    const auto per_frame = [&](double seconds) {
      return processed > 0 ? seconds / processed : 0.0;
    };
    RunReport r;
    if (const auto it = write_.custom_layer_data.find("input");
        it != write_.custom_layer_data.end()) {
      r.input = it->second;
    }
    r.labels = models_ ? "models" : options_.given_labels.Text();
    r.frames = result.frames;
    r.processed_frames = pipeline_->frames();
    r.segmented_frames = pipeline_->segmented_frames();
    r.resumed_frames = result.resumed_frames;
    r.skipped_frames = skipped_;
    r.seconds = result.seconds;
    r.frames_per_second = result.seconds > 0 ? processed / result.seconds : 0.0;
    r.seconds_per_frame = {per_frame(s.read),    per_frame(s.segment),
                           per_frame(s.track),   per_frame(s.fuse),
                           per_frame(s.volumes), per_frame(s.overlay),
                           per_frame(s.write)};
    r.timing = TimingJson(timing_, s, pipeline_->cpu_seconds(), result.seconds);
    r.peak_rss_mb = static_cast<double>(PeakRssBytes()) / (1 << 20);
    r.scene =
        ParseObjectRecords(result.scene.objects_json, out_dir_ / "report.json");
    for (const ObjectRecord& object : r.scene) {
      ++r.objects_per_class[object.class_name];
    }
    r.objects = result.scene.objects - result.scene.structure;
    r.structure = result.scene.structure;
    r.surface_patches = result.scene.patches;
    r.skipped_empty_objects = result.scene.skipped_empty_objects;
    r.people = result.scene.people;
    r.tracks = result.tracks;
    r.snapshots = snapshots_;
    r.gravity = GravityJson(result.scene.gravity, result.scene.upright_matrix);
    r.options = result.scene.options_text;
    r.version = SEMREC_VERSION;
    r.models = ModelRecords(registry_, options_.pipeline);
    r.poses = poses_;
    r.fusion_events = fuse::FusionEventsJson(pipeline_->scene().fusion(),
                                             pipeline_->classes());
    r.map_objects = fuse::MapResolutionJson(pipeline_->scene().fusion(),
                                            pipeline_->classes());
    if (models_) {
      r.map_guidance = MapGuidance();
      r.object_detector = ObjectDetector();
    }
    return r;
  }

  // Without guidance every segmented frame is full; the counts of encoder
  // calls and prompts compare the two.
  MapGuidanceReport MapGuidance() const {
    const GuidanceCounts& g = pipeline_->guidance_counts();
    const size_t guided = g.partial + g.projection;
    MapGuidanceReport out;
    out.enabled = options_.pipeline.map_guidance;
    out.full_frames = out.enabled ? g.full : pipeline_->segmented_frames();
    out.partial_frames = g.partial;
    out.projection_frames = g.projection;
    out.disagreement_frames = g.disagreement;
    out.encoder_calls = g.encoder_calls;
    out.prompts_decoded = g.prompts_decoded;
    out.mean_unexplained_share =
        guided > 0 ? g.unexplained_share_sum / static_cast<double>(guided)
                   : 0.0;
    return out;
  }

  ObjectDetectorReport ObjectDetector() const {
    const segment::ObjectDetectorOptions& o =
        options_.pipeline.segmenter.objects;
    const ObjectDetectionCounts& c = pipeline_->object_counts();
    ObjectDetectorReport out;
    if (o.enabled()) out.model = o.model;
    out.score_threshold = o.score_threshold;
    out.weight = o.weight;
    out.stuff_yields = o.stuff_yields;
    out.detections = c.detections;
    out.matched_masks = c.matched;
    out.added_masks = c.added;
    out.parts = c.parts;
    out.parts_joined = c.parts_joined;
    out.frames_sharing_the_people_pass = c.shared_passes;
    return out;
  }

  const io::SequenceReader& reader_;
  const infer::ModelRegistry* registry_;
  const RunOptions& options_;
  const fs::path out_dir_;
  const bool models_;
  const Stopwatch run_time_;
  RunTiming timing_;
  std::unique_ptr<fuse::SegmentationSource> source_;
  std::optional<PersonMapSource> person_maps_;
  std::optional<ScenePipeline> pipeline_;
  std::optional<odometry::PoseTracker> tracker_;
  std::set<uint16_t> dynamic_ids_;
  std::vector<io::StampedPose> estimated_;
  PoseReport poses_;
  CheckpointStore store_{out_dir_ / "checkpoint"};
  size_t begin_ = 0;
  SceneWriteOptions write_, snapshot_;
  std::optional<Progress> progress_;  // from the first frame on
  std::vector<SkippedFrame> skipped_;
  size_t snapshots_ = 0, resumed_frames_ = 0;
  double read_seconds_ = 0.0;
  std::future<Loaded> next_;
  std::future<void> integrating_;
  bool tick_pending_ = false;
};

}  // namespace

RunResult RunSequence(const io::SequenceReader& reader,
                      const infer::ModelRegistry* registry,
                      const RunOptions& options, const fs::path& out_dir,
                      const ProgressOptions& progress_options) {
  options.Check();
  return SequenceRun(reader, registry, options, out_dir, progress_options)
      .Run();
}

std::string RunSummaryTable(const RunResult& result, const fs::path& out_dir) {
  const RunReport& r = result.report;
  std::string out = fmt::format(
      "{} frames ({} segmented, {} skipped{}) in {:.1f} s = {:.2f} frames/s, "
      "peak memory {:.0f} MB\n",
      r.frames, r.segmented_frames, result.skipped_frames,
      result.resumed_frames > 0
          ? fmt::format(", {} replayed from the checkpoint",
                        result.resumed_frames)
          : "",
      result.seconds, r.frames_per_second, r.peak_rss_mb);
  out += "  seconds per frame:";
  for (const auto& [stage, seconds] : r.seconds_per_frame.Named()) {
    out += fmt::format(" {} {:.3f}", stage, seconds);
  }
  out += "\n";
  out += fmt::format("  {} objects + {} structure:", r.objects, r.structure);
  for (const auto& [name, count] : r.objects_per_class) {
    out += fmt::format(" {} {}", count, name);
  }
  out += "\n";
  if (r.map_guidance && r.map_guidance->enabled) {
    const MapGuidanceReport& g = *r.map_guidance;
    out += fmt::format(
        "  map guidance: {} full, {} partial, {} by projection alone; {} "
        "encoder calls, {} prompts decoded\n",
        g.full_frames, g.partial_frames, g.projection_frames, g.encoder_calls,
        g.prompts_decoded);
  }
  if (r.poses.source == "estimated") {
    out += fmt::format(
        "  camera poses estimated ({}): {} keyframes, {} frames not "
        "tracked, {:.0f} ms per frame\n",
        r.poses.method, r.poses.keyframes, r.poses.lost_frames,
        r.processed_frames > 0
            ? 1000 * r.poses.seconds / static_cast<double>(r.processed_frames)
            : 0.0);
  }
  out += fmt::format("  {} people prims, {} tracks in tracks.txt\n",
                     result.scene.people, result.tracks);
  std::string written;
  for (const char* name : {"objects/", "overlay/", "tracks.txt", "poses.txt"}) {
    if (fs::exists(out_dir / name)) written += fmt::format("{}, ", name);
  }
  out += fmt::format(
      "  wrote {}/scene.usda (+ static.usda, dynamic.usda), {}report.json\n",
      out_dir.string(), written);
  return out;
}

}  // namespace semrec::pipeline
