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

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/core/sha256.h"
#include "semrec/core/stopwatch.h"
#include "semrec/fuse/fuse_sequence.h"
#include "semrec/infer/onnx_model.h"
#include "semrec/io/image_io.h"
#include "semrec/io/mot_io.h"
#include "semrec/pipeline/checkpoint.h"
#include "semrec/pipeline/people_3d.h"

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
nlohmann::json ModelsJson(const infer::ModelRegistry* registry,
                          const ScenePipelineOptions& options) {
  nlohmann::json out = nlohmann::json::array();
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
    out.push_back({{"name", name},
                   {"file", file.string()},
                   {"sha256", sha256},
                   {"sha256_registered", !e.sha256.empty()}});
  }
  return out;
}

}  // namespace

void RunOptions::Check() const {
  pipeline.Check();
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

RunResult RunSequence(const io::SequenceReader& reader,
                      const infer::ModelRegistry* registry,
                      const RunOptions& options, const fs::path& out_dir,
                      const ProgressOptions& progress_options) {
  options.Check();
  const Stopwatch run_time;
  RunTiming timing;
  const bool models =
      options.pipeline.labels == ScenePipelineOptions::Labels::kModels;
  if (!options.resume) RequireEmptyOrOverwrite(out_dir, options.overwrite);
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec) {
    throw IoError(out_dir, "cannot create output folder: " + ec.message());
  }

  // Given labels: the sequence's own layers (or a label folder).
  std::unique_ptr<fuse::SegmentationSource> source;
  std::optional<PersonMapSource> person_maps;
  if (!models) {
    source = fuse::SegmentationSource::Create(options.given_labels, reader);
    if (options.pipeline.track_people) {
      std::string people = options.given_people;
      if (people.empty() &&
          reader.index().frames.front().layers.contains("person")) {
        people = "gt";
      }
      if (!people.empty()) person_maps.emplace(people, reader);
    }
  }
  ScenePipeline pipeline(registry, source ? &source->classes() : nullptr,
                         options.pipeline);

  CheckpointStore store(out_dir / "checkpoint");
  Sha256 config_hash;
  config_hash.Update(options.resume_key.empty() ? options.config_text
                                                : options.resume_key);
  const RunIdentity identity = {reader.root().string(), reader.layout(),
                                reader.size(), config_hash.HexDigest()};
  const size_t begin = options.resume ? store.Resume(identity) : 0;
  if (!options.resume) store.Start(identity);
  if (options.resume) {
    spdlog::info(
        "resuming: {} of {} frames are done; replaying them without "
        "the models",
        begin, reader.size());
  }
  WriteTextFileAtomic(out_dir / "run.yaml", options.config_text);

  SceneWriteOptions write =
      SceneWriteOptions::For(reader, options.write_ply, options.usdz);
  write.custom_layer_data["config"] = OneLine(options.config_text);
  SceneWriteOptions snapshot = write;
  snapshot.write_ply = false;
  snapshot.usdz = false;
  write.glb = options.glb;
  snapshot.glb = false;

  RunResult result;
  nlohmann::json skipped = nlohmann::json::array();
  size_t snapshots = 0;
  double read_seconds = 0.0;
  Progress progress("run", reader.size(), progress_options);
  // Reading and decoding frame i + 1 overlaps the work on frame i.
  struct Loaded {
    PipelineInput input;
    std::exception_ptr error;
    double seconds = 0.0, cpu = 0.0;
  };
  const auto load = [&](size_t i) {
    Loaded loaded;
    const Stopwatch read_time;
    const double read_cpu = ThreadCpuSeconds();
    loaded.input.name =
        reader.index().frames[i].color_path.stem().string() + ".png";
    try {
      loaded.input.frame = reader.Read(i);
      if (!models) {
        loaded.input.labels = source->Get(reader, i);
        if (person_maps) loaded.input.person_ids = person_maps->Get(i);
      }
    } catch (...) {
      loaded.error = std::current_exception();
    }
    loaded.seconds = read_time.Elapsed();
    loaded.cpu = ThreadCpuSeconds() - read_cpu;
    return loaded;
  };
  std::future<Loaded> next;
  const auto start_loading = [&](size_t i) {
    if (i < reader.size()) {
      next = std::async(
          options.prefetch ? std::launch::async : std::launch::deferred, load,
          i);
    }
  };
  // Fusion and volumes of frame i run on another thread while the models
  // work on frame i + 1 (each side keeps frame order).
  std::future<void> integrating;
  bool tick_pending = false;
  const auto wait_integrating = [&] {
    const Stopwatch wait;
    if (integrating.valid()) integrating.get();
    timing.wait_integration += wait.Elapsed();
    if (tick_pending) {
      progress.set_detail(StageDetail(pipeline.seconds(), pipeline.frames()));
      progress.Tick();
      tick_pending = false;
    }
  };
  timing.setup = run_time.Elapsed();
  start_loading(0);
  for (size_t i = 0; i < reader.size(); ++i) {
    const Stopwatch wait_frame;
    Loaded loaded = next.get();
    timing.wait_frames += wait_frame.Elapsed();
    start_loading(i + 1);
    PipelineInput& input = loaded.input;
    const bool replay = i < begin;
    std::optional<CheckpointFrame> saved;
    if (replay) {
      saved = store.Load(i);
      if (saved->skipped) {
        wait_integrating();
        skipped.push_back({{"frame", i}, {"reason", *saved->skipped}});
        progress.Tick();
        continue;
      }
    }
    read_seconds += loaded.seconds;
    timing.read_cpu += loaded.cpu;
    if (loaded.error) {
      wait_integrating();
      try {
        std::rethrow_exception(loaded.error);
      } catch (const FileError& e) {
        if (options.strict || replay) throw;
        spdlog::warn("skipping frame {}: {}", i, e.what());
        skipped.push_back({{"frame", i}, {"reason", e.what()}});
        store.Record(i, {std::string(e.what()), std::nullopt});
        progress.Tick();
        continue;
      }
    }
    if (replay && models) input.replay = std::move(saved->outputs);
    std::string name = input.name;
    const Stopwatch prepare;
    PreparedFrame prepared = pipeline.Prepare(std::move(input));
    timing.prepare += prepare.Elapsed();
    wait_integrating();
    const auto integrate = [&, i, replay, name = std::move(name),
                            prepared = std::move(prepared)]() mutable {
      const PipelineFrameResult frame = pipeline.Integrate(std::move(prepared));
      if (replay) {
        ++result.resumed_frames;
        return;
      }
      // The overlay's PNG and the checkpoint's, side by side.
      tbb::task_group files;
      if (!frame.overlay.empty()) {
        files.run(
            [&] { io::WritePng(out_dir / "overlay" / name, frame.overlay); });
      }
      store.Record(
          i, {std::nullopt, models ? std::optional<ModelOutputs>(frame.outputs)
                                   : std::nullopt});
      files.wait();
      if (options.checkpoint_every > 0 &&
          (i + 1) % options.checkpoint_every == 0) {
        store.Commit(i + 1);
      }
      if (options.snapshot_every > 0 && (i + 1) % options.snapshot_every == 0 &&
          i + 1 < reader.size()) {
        pipeline.Write(out_dir, snapshot);
        ++snapshots;
      }
    };
    integrating =
        std::async(options.overlap ? std::launch::async : std::launch::deferred,
                   [&timing, integrate = std::move(integrate)]() mutable {
                     StageWatch watch;
                     integrate();
                     const StageWatch::Lap lap = watch.Next();
                     timing.integrate_wall += lap.wall;
                     timing.integrate_cpu += lap.cpu;
                   });
    tick_pending = true;
  }
  wait_integrating();
  progress.Finish();
  const Stopwatch finish;
  store.Commit(reader.size());

  pipeline.Finish();
  result.scene = pipeline.Write(out_dir, write);
  const std::vector<io::MotBox> tracks = pipeline.Tracks();
  io::WriteMotFile(out_dir / "tracks.txt", tracks);
  std::set<int> track_ids;
  for (const io::MotBox& b : tracks) track_ids.insert(b.id);
  result.tracks = track_ids.size();
  result.frames = reader.size();
  result.skipped_frames = skipped.size();
  timing.finish = finish.Elapsed();
  result.seconds = run_time.Elapsed();

  // Report.
  StageSeconds s = pipeline.seconds();
  s.read = read_seconds;
  const double processed = static_cast<double>(pipeline.frames());
  std::map<std::string, int> per_class;
  for (const auto& object : result.scene.objects_json) {
    ++per_class[object.at("class").get<std::string>()];
  }
  const auto per_frame = [&](double seconds) {
    return processed > 0 ? seconds / processed : 0.0;
  };
  result.report = {
      {"input", write.custom_layer_data["input"]},
      {"labels", models ? "models" : options.given_labels},
      {"frames", result.frames},
      {"processed_frames", pipeline.frames()},
      {"segmented_frames", pipeline.segmented_frames()},
      {"resumed_frames", result.resumed_frames},
      {"skipped_frames", skipped},
      {"seconds", result.seconds},
      {"frames_per_second",
       result.seconds > 0 ? processed / result.seconds : 0.0},
      {"seconds_per_frame",
       {{"read", per_frame(s.read)},
        {"segment", per_frame(s.segment)},
        {"track", per_frame(s.track)},
        {"fuse", per_frame(s.fuse)},
        {"volumes", per_frame(s.volumes)},
        {"overlay", per_frame(s.overlay)},
        {"write", per_frame(s.write)}}},
      {"timing", TimingJson(timing, s, pipeline.cpu_seconds(), result.seconds)},
      {"peak_rss_mb", static_cast<double>(PeakRssBytes()) / (1 << 20)},
      {"objects", result.scene.objects - result.scene.structure},
      {"structure", result.scene.structure},
      {"objects_per_class", per_class},
      {"people", result.scene.people},
      {"tracks", result.tracks},
      {"snapshots", snapshots},
      {"gravity",
       GravityJson(result.scene.gravity, result.scene.upright_matrix)},
      {"options", result.scene.options_text},
      {"config", "run.yaml"},
      {"version", SEMREC_VERSION},
      {"models", ModelsJson(registry, options.pipeline)},
      {"scene", result.scene.objects_json},
      {"fusion_events",
       fuse::FusionEventsJson(pipeline.scene().fusion(), pipeline.classes())},
      {"map_objects",
       fuse::MapResolutionJson(pipeline.scene().fusion(), pipeline.classes())}};
  if (models) {
    // Without guidance every segmented frame is full; the counts of encoder
    // calls and prompts compare the two.
    const GuidanceCounts& g = pipeline.guidance_counts();
    const size_t guided = g.partial + g.projection;
    result.report["map_guidance"] = {
        {"enabled", options.pipeline.map_guidance},
        {"full_frames",
         options.pipeline.map_guidance ? g.full : pipeline.segmented_frames()},
        {"partial_frames", g.partial},
        {"projection_frames", g.projection},
        {"disagreement_frames", g.disagreement},
        {"encoder_calls", g.encoder_calls},
        {"prompts_decoded", g.prompts_decoded},
        {"mean_unexplained_share",
         guided > 0 ? g.unexplained_share_sum / static_cast<double>(guided)
                    : 0.0}};
    const segment::ObjectDetectorOptions& o =
        options.pipeline.segmenter.objects;
    const ObjectDetectionCounts& c = pipeline.object_counts();
    result.report["object_detector"] = {
        {"model", o.enabled() ? nlohmann::json(o.model) : nlohmann::json()},
        {"score_threshold", o.score_threshold},
        {"weight", o.weight},
        {"stuff_yields", o.stuff_yields},
        {"detections", c.detections},
        {"matched_masks", c.matched},
        {"added_masks", c.added},
        {"parts", c.parts},
        {"parts_joined", c.parts_joined},
        {"frames_sharing_the_people_pass", c.shared_passes}};
  }
  WriteTextFileAtomic(out_dir / "report.json", result.report.dump(2) + "\n");
  return result;
}

std::string RunSummaryTable(const RunResult& result, const fs::path& out_dir) {
  const nlohmann::json& r = result.report;
  std::string out = fmt::format(
      "{} frames ({} segmented, {} skipped{}) in {:.1f} s = {:.2f} frames/s, "
      "peak memory {:.0f} MB\n",
      r.at("frames").get<size_t>(), r.at("segmented_frames").get<size_t>(),
      result.skipped_frames,
      result.resumed_frames > 0
          ? fmt::format(", {} replayed from the checkpoint",
                        result.resumed_frames)
          : "",
      result.seconds, r.at("frames_per_second").get<double>(),
      r.at("peak_rss_mb").get<double>());
  out += "  seconds per frame:";
  for (const char* stage :
       {"read", "segment", "track", "fuse", "volumes", "overlay", "write"}) {
    out += fmt::format(" {} {:.3f}", stage,
                       r.at("seconds_per_frame").at(stage).get<double>());
  }
  out += "\n";
  out +=
      fmt::format("  {} objects + {} structure:", r.at("objects").get<size_t>(),
                  r.at("structure").get<size_t>());
  for (const auto& [name, count] : r.at("objects_per_class").items()) {
    out += fmt::format(" {} {}", count.get<int>(), name);
  }
  out += "\n";
  if (r.contains("map_guidance") && r["map_guidance"].value("enabled", false)) {
    const nlohmann::json& g = r.at("map_guidance");
    out += fmt::format(
        "  map guidance: {} full, {} partial, {} by projection alone; {} "
        "encoder calls, {} prompts decoded\n",
        g.at("full_frames").get<size_t>(), g.at("partial_frames").get<size_t>(),
        g.at("projection_frames").get<size_t>(),
        g.at("encoder_calls").get<size_t>(),
        g.at("prompts_decoded").get<size_t>());
  }
  out += fmt::format("  {} people prims, {} tracks in tracks.txt\n",
                     result.scene.people, result.tracks);
  out += fmt::format(
      "  wrote {0}/scene.usda (+ static.usda, dynamic.usda), objects/, "
      "overlay/, tracks.txt, report.json\n",
      out_dir.string());
  return out;
}

}  // namespace semrec::pipeline
