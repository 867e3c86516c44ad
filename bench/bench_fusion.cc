// Semantics-guided fusion: the paper's runtime table and accuracy, reproduced
// on synthetic scenes and on real frames.
//   bench_fusion [frames=10] [office_frames=300] [sequence label_dir]
// 1. six-objects preset (640x480, Kinect noise): per frame, scene and frame
//    points (at the 10 cm comparison resolution), distance computations
//    without and with labels and their ratio (the paper's reduction factor,
//    1.52-2.15x, mean 1.81x), wall time of the comparison stage for brute
//    force and fast, without and with labels, all in this one run.
// 2. Accuracy after 5 frames: C2C of the fused clouds to the exact surfaces
//    (analytic distance) and to the dense GT samples (as CloudCompare would),
//    and per-object merge correctness.
// 3. office preset: fast vs brute force wall time (target >= 50x), with
//    identical merges; each method run 3 times, the median reported.
// 4. With a sequence and a label folder (`semrec segment` output, or any
//    folder `semrec fuse --labels` reads): the table of 1 on real frames,
//    using the frames that have a label file.
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>

#include "semrec/core/stopwatch.h"
#include "semrec/eval/c2c.h"
#include "semrec/fuse/fusion.h"
#include "semrec/fuse/segments.h"
#include "semrec/io/ply_io.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/synth/generator.h"

namespace fs = std::filesystem;
using namespace semrec;

namespace {

struct Prepared {
  std::vector<std::vector<fuse::FrameSegment>> frames;
  synth::Scene scene;
  fs::path dir;
};

std::vector<std::vector<fuse::FrameSegment>> Extract(
    const io::SequenceReader& reader, const fuse::SegmentationSource& source,
    const fs::path& label_dir) {
  std::vector<std::vector<fuse::FrameSegment>> frames;
  for (size_t i = 0; i < reader.size(); ++i) {
    const fs::path depth = reader.index().frames[i].depth_path;
    if (!label_dir.empty() &&
        !fs::exists(label_dir / "instance" / depth.filename())) {
      continue;  // not segmented (e.g. `semrec segment --stride`)
    }
    frames.push_back(fuse::ExtractFrameSegments(
        reader.Read(i), source.Get(reader, i), source.classes(), {}));
  }
  return frames;
}

Prepared Prepare(const std::string& preset, int frames, const fs::path& dir) {
  synth::SynthOptions o = synth::SynthOptions::Preset(preset);
  o.frames = frames;
  o.overwrite = true;
  o.gt_structure_spacing_m = 0.005;
  ProgressOptions quiet;
  quiet.mode = ProgressOptions::Mode::kOff;
  synth::WriteSyntheticSequence(o, dir, quiet);
  Prepared p;
  p.dir = dir;
  synth::SceneOptions scene_options = o.scene;
  scene_options.seed = o.seed;
  p.scene = synth::GenerateScene(scene_options);
  const io::SequenceReader reader = io::SequenceReader::Open(dir);
  p.frames =
      Extract(reader, *fuse::SegmentationSource::Create("gt", reader), {});
  return p;
}

struct Run {
  std::vector<fuse::FrameFusionStats> stats;
  double seconds = 0.0;
  double compare_seconds = 0.0;
  std::vector<fuse::SceneSegment> segments;
};

Run Fuse(const std::vector<std::vector<fuse::FrameSegment>>& input, bool gating,
         fuse::FusionOptions::Method method, size_t frames) {
  fuse::FusionOptions options;
  options.label_gating = gating;
  options.method = method;
  fuse::SceneFusion fusion(options);
  Run run;
  const Stopwatch clock;
  for (size_t i = 0; i < std::min(frames, input.size()); ++i) {
    run.stats.push_back(fusion.Integrate(input[i], i));
    run.compare_seconds += run.stats.back().compare_seconds;
  }
  run.seconds = clock.Elapsed();
  run.segments = fusion.segments();
  return run;
}

bool SameSegments(const std::vector<fuse::SceneSegment>& a,
                  const std::vector<fuse::SceneSegment>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (a[i].id != b[i].id || a[i].class_id != b[i].class_id ||
        a[i].points != b[i].points) {
      return false;
    }
  }
  return true;
}

// The paper's runtime table: per frame, points, distance computations without
// and with labels, and the comparison stage's wall time for each method.
void PrintRuntimeTable(
    const std::vector<std::vector<fuse::FrameSegment>>& input) {
  using Method = fuse::FusionOptions::Method;
  const size_t n = input.size();
  const Run brute_ungated = Fuse(input, false, Method::kBruteForce, n);
  const Run brute_gated = Fuse(input, true, Method::kBruteForce, n);
  const Run fast_ungated = Fuse(input, false, Method::kFast, n);
  const Run fast_gated = Fuse(input, true, Method::kFast, n);
  std::printf("%5s %7s %7s %8s %14s %14s %9s %10s %10s %9s %9s\n", "frame",
              "scene", "frame", "segments", "dist(no lab)", "dist(labels)",
              "reduction", "brute(ms)", "brute+lab", "fast", "fast+lab");
  double reduction_sum = 0.0;
  int reduction_n = 0;
  for (size_t i = 0; i < brute_gated.stats.size(); ++i) {
    const auto& u = brute_ungated.stats[i];
    const auto& g = brute_gated.stats[i];
    const double reduction =
        g.distance_computations_done > 0
            ? static_cast<double>(u.distance_computations_done) /
                  g.distance_computations_done
            : 0.0;
    if (g.distance_computations_done > 0) {
      reduction_sum += reduction, ++reduction_n;
    }
    std::printf(
        "%5zu %7zu %7zu %8zu %14llu %14llu %8.2fx %10.2f %10.2f %9.2f %9.2f\n",
        i, g.scene_points, g.frame_points, g.frame_segments,
        static_cast<unsigned long long>(u.distance_computations_done),
        static_cast<unsigned long long>(g.distance_computations_done),
        reduction, 1e3 * u.compare_seconds, 1e3 * g.compare_seconds,
        1e3 * fast_ungated.stats[i].compare_seconds,
        1e3 * fast_gated.stats[i].compare_seconds);
  }
  std::printf(
      "mean reduction factor with labels: %.2fx over %d frames (paper: 1.81x, "
      "range 1.52-2.15x)\n",
      reduction_n > 0 ? reduction_sum / reduction_n : 0.0, reduction_n);
  std::printf(
      "comparison stage: brute force %.3f s, + labels %.3f s (%.2fx); fast "
      "%.3f s, + labels %.3f s (%.1fx vs brute force + labels)\n",
      brute_ungated.compare_seconds, brute_gated.compare_seconds,
      brute_ungated.compare_seconds / brute_gated.compare_seconds,
      fast_ungated.compare_seconds, fast_gated.compare_seconds,
      brute_gated.compare_seconds / fast_gated.compare_seconds);
  std::printf(
      "whole fusion (incl. downsampling, merging): brute force %.3f s, + "
      "labels %.3f s, fast + labels %.3f s (%.1fx); identical result: %s\n",
      brute_ungated.seconds, brute_gated.seconds, fast_gated.seconds,
      brute_gated.seconds / fast_gated.seconds,
      SameSegments(brute_gated.segments, fast_gated.segments) ? "yes" : "NO");
}

}  // namespace

int main(int argc, char** argv) {
  const int frames = argc > 1 ? std::stoi(argv[1]) : 10;
  const int office_frames = argc > 2 ? std::stoi(argv[2]) : 300;
  const fs::path tmp = fs::temp_directory_path() / "semrec_bench_fusion";
  using Method = fuse::FusionOptions::Method;

  std::printf("== six-objects, %d frames, 640x480, Kinect noise ==\n", frames);
  const Prepared six = Prepare("six-objects", frames, tmp / "six");
  PrintRuntimeTable(six.frames);

  // Accuracy after 5 frames.
  const Run five = Fuse(six.frames, true, Method::kFast, 5);
  std::vector<Eigen::Vector3f> fused;
  std::vector<double> exact;
  for (const auto& s : five.segments) {
    for (const auto& p : s.points) {
      fused.push_back(p);
      double best = 1e9;
      for (const auto& o : six.scene.objects) {
        best = std::min(best, o.DistanceToSurface(p.cast<double>()));
      }
      exact.push_back(best);
    }
  }
  const eval::DistanceStats e = eval::Summarize(exact);
  const eval::DistanceStats c = eval::Summarize(eval::CloudToCloudDistances(
      fused, io::ReadPly(six.dir / "gt/surface_points.ply").points));
  std::printf("accuracy after 5 frames (%zu fused points, %zu segments):\n",
              fused.size(), five.segments.size());
  std::printf(
      "  to the exact surfaces:     mean %.1f mm, std %.1f mm, median %.1f "
      "mm\n",
      1e3 * e.mean_m, 1e3 * e.std_m, 1e3 * e.median_m);
  std::printf(
      "  C2C to GT samples (5 mm):  mean %.1f mm, std %.1f mm (paper: 25.3 / "
      "19.1 mm)\n",
      1e3 * c.mean_m, 1e3 * c.std_m);
  std::map<std::string, int> per_class;
  for (const auto& s : five.segments) {
    ++per_class[synth::SynthClasses().Get(s.class_id).name];
  }
  std::printf("  segments per class:");
  for (const auto& [name, n] : per_class) {
    std::printf(" %s %d", name.c_str(), n);
  }
  std::printf("\n");

  if (office_frames > 0) {
    std::printf("\n== office, %d frames: fast vs brute force (labels on) ==\n",
                office_frames);
    const Prepared office = Prepare("office", office_frames, tmp / "office");
    // Median of 3 runs each: single runs on a shared 2-core machine vary by
    // 20%.
    auto median_run = [&](Method method) {
      std::vector<Run> runs;
      for (int r = 0; r < 3; ++r) {
        runs.push_back(Fuse(office.frames, true, method, office_frames));
      }
      std::sort(runs.begin(), runs.end(), [](const Run& x, const Run& y) {
        return x.compare_seconds < y.compare_seconds;
      });
      return runs[1];
    };
    const Run b = median_run(Method::kBruteForce);
    const Run f = median_run(Method::kFast);
    uint64_t done_b = 0, done_f = 0;
    for (const auto& s : b.stats) done_b += s.distance_computations_done;
    for (const auto& s : f.stats) done_f += s.distance_computations_done;
    std::printf(
        "comparison stage: brute force %.3f s (%llu distances), fast %.3f s "
        "(%llu "
        "distances): %.1fx faster (target >= 50x; median of 3 runs)\n",
        b.compare_seconds, static_cast<unsigned long long>(done_b),
        f.compare_seconds, static_cast<unsigned long long>(done_f),
        b.compare_seconds / f.compare_seconds);
    std::printf(
        "whole fusion: brute force %.3f s, fast %.3f s: %.1fx; %zu segments; "
        "identical "
        "result: %s\n",
        b.seconds, f.seconds, b.seconds / f.seconds, f.segments.size(),
        SameSegments(b.segments, f.segments) ? "yes" : "NO");
  }
  if (argc > 4) {
    const fs::path sequence = argv[3], labels = argv[4];
    const io::SequenceReader reader = io::SequenceReader::Open(sequence);
    const auto source = fuse::SegmentationSource::Create(labels, reader);
    const auto real = Extract(reader, *source, labels);
    std::printf("\n== real frames: %s, labels %s (%zu frames) ==\n",
                sequence.c_str(), labels.c_str(), real.size());
    PrintRuntimeTable(real);
  }
  fs::remove_all(tmp);
  return 0;
}
