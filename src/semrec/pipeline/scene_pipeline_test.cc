#include "semrec/pipeline/scene_pipeline.h"

#include <algorithm>
#include <map>
#include <set>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/eval/c2c.h"
#include "semrec/io/image_io.h"
#include "semrec/io/mot_io.h"
#include "semrec/io/ply_io.h"
#include "semrec/pipeline/checkpoint.h"
#include "semrec/pipeline/people_3d.h"
#include "semrec/pipeline/reconstruct.h"
#include "semrec/pipeline/run_sequence.h"
#include "semrec/pipeline/track_images.h"
#include "semrec/synth/generator.h"
#include "semrec/testing/small_scene.h"
#include "semrec/testing/test_util.h"

namespace fs = std::filesystem;

namespace semrec::pipeline {
namespace {

using testing::SmallScene;

// Largest distance from a sample of `a`'s points (about 400) to the nearest
// point of `b`, by brute force.
double MaxNearestDistance(const std::vector<Eigen::Vector3f>& a,
                          const std::vector<Eigen::Vector3f>& b) {
  double worst = 0.0;
  const size_t step = std::max<size_t>(1, a.size() / 400);
  for (size_t i = 0; i < a.size(); i += step) {
    double best = 1e9;
    for (const auto& q : b)
      best = std::min(best, static_cast<double>((a[i] - q).norm()));
    worst = std::max(worst, best);
  }
  return worst;
}

// Two volumes combined by Absorb give the mesh one volume of all the frames
// gives.
TEST(TsdfAbsorb, EqualsIntegratingAllFramesIntoOneVolume) {
  testing::TempDir dir;
  synth::SynthOptions o = SmallScene("six-objects", 6);
  o.noise.enabled = false;
  synth::WriteSyntheticSequence(o, dir / "seq", testing::QuietProgress());
  const io::SequenceReader reader = io::SequenceReader::Open(dir / "seq");
  mesh::TsdfOptions tsdf{0.04, 0.12, 4.0, true};
  mesh::TsdfIntegrator all(tsdf), first(tsdf), second(tsdf);
  for (size_t i = 0; i < reader.size(); ++i) {
    const Frame frame = reader.Read(i);
    all.Integrate(frame);
    (i % 2 == 0 ? first : second).Integrate(frame);
  }
  first.Absorb(&second);
  EXPECT_EQ(first.num_integrated(), all.num_integrated());
  const auto a = all.ExtractMesh();
  const auto b = first.ExtractMesh();
  ASSERT_GT(a->vertices_.size(), 1000u);
  // Same voxels, same weighted averages up to rounding: the same surface.
  EXPECT_NEAR(static_cast<double>(b->vertices_.size()),
              static_cast<double>(a->vertices_.size()),
              0.001 * a->vertices_.size());
  std::vector<Eigen::Vector3f> va, vb;
  for (const auto& v : a->vertices_) va.push_back(v.cast<float>());
  for (const auto& v : b->vertices_) vb.push_back(v.cast<float>());
  EXPECT_LT(MaxNearestDistance(vb, va), 1e-4);
  // Absorbing a different grid is refused.
  mesh::TsdfIntegrator other({0.05, 0.15, 4.0, true});
  EXPECT_THROW(first.Absorb(&other), InvalidArgument);
}

// The streaming reconstruction (volumes combined when fusion merges objects)
// matches the two-pass one (volumes built afterwards with the final ids), on
// noisy labels where fusion merges parts after they were integrated.
TEST(SceneBuilder, StreamingMatchesTwoPass) {
  testing::TempDir dir;
  synth::SynthOptions o = SmallScene("six-objects", 16);
  o.write_noisy_labels = true;
  synth::WriteSyntheticSequence(o, dir / "seq", testing::QuietProgress());
  const io::SequenceReader reader = io::SequenceReader::Open(dir / "seq");
  const auto source = fuse::SegmentationSource::Create(
      (dir / "seq/labels_noisy").string(), reader);
  ReconstructOptions options;
  const ReconstructResult streaming = Reconstruct(
      reader, *source, options, dir / "stream", testing::QuietProgress());
  options.scene.stream_volumes = false;
  const ReconstructResult two_pass = Reconstruct(
      reader, *source, options, dir / "two", testing::QuietProgress());
  const auto s1 =
      nlohmann::json::parse(ReadTextFile(dir / "stream/summary.json"));
  const auto s2 = nlohmann::json::parse(ReadTextFile(dir / "two/summary.json"));
  // The test means something only if fusion merged objects along the way.
  size_t merges = 0;
  for (const auto& e : s1["fusion_events"]) {
    merges += e["event"] != "dropped" ? 1 : 0;
  }
  EXPECT_GT(merges, 0u);
  ASSERT_EQ(streaming.scene.objects, two_pass.scene.objects);
  ASSERT_EQ(s1["objects"].size(), s2["objects"].size());
  for (size_t k = 0; k < s1["objects"].size(); ++k) {
    const auto& a = s1["objects"][k];
    const auto& b = s2["objects"][k];
    ASSERT_EQ(a["id"], b["id"]);
    EXPECT_EQ(a["class"], b["class"]);
    const double va = a["vertices"].get<double>();
    const double vb = b["vertices"].get<double>();
    // Tolerance: rounding in the weighted averages moves a few zero
    // crossings; 1% of the vertices and 1 mm.
    EXPECT_NEAR(va, vb, std::max(2.0, 0.01 * vb)) << a["id"];
    const io::PlyData ma =
        io::ReadPly(dir / "stream" / a["ply"].get<std::string>());
    const io::PlyData mb =
        io::ReadPly(dir / "two" / b["ply"].get<std::string>());
    EXPECT_LT(MaxNearestDistance(ma.points, mb.points), 1e-3) << a["id"];
  }
  // `semrec mesh` is RunSequence with the given labels: the same scene as the
  // streaming reconstruction, object for object.
  RunOptions run;
  run.pipeline.labels = ScenePipelineOptions::Labels::kGiven;
  run.pipeline.track_people = false;
  run.pipeline.overlays = false;
  run.given_labels =
      fuse::LabelSpec::Parse((dir / "seq/labels_noisy").string());
  run.config_text = "labels: noisy\n";
  const RunResult r =
      RunSequence(reader, nullptr, run, dir / "run", testing::QuietProgress());
  ASSERT_EQ(r.report.scene.size(), s1["objects"].size());
  for (size_t k = 0; k < r.report.scene.size(); ++k) {
    const ObjectRecord& o = r.report.scene[k];
    const auto& a = s1["objects"][k];
    EXPECT_EQ(o.id, a["id"].get<uint32_t>());
    EXPECT_EQ(o.class_name, a["class"].get<std::string>());
    EXPECT_EQ(o.vertices, a["vertices"].get<size_t>()) << o.id;
    EXPECT_EQ(o.triangles, a["triangles"].get<size_t>()) << o.id;
  }
}

// Ground-truth labels through the whole pipeline (the paper's Hypersim
// setting) on the people preset: the objects with the right classes, no
// person in the static map, people with the ground truth's ids as
// time-sampled prims, tracks.txt equal to the ground truth's boxes.
TEST(RunSequence, GroundTruthLabelsAndPeople) {
  testing::TempDir dir;
  synth::SynthOptions o = SmallScene("people", 40);
  o.noise.max_depth_m = 8.0;  // the furniture stands 4-7 m from the camera
  o.gt_object_spacing_m = 0.01;
  o.noise.enabled = false;  // 4-7 m away, sensor noise would dominate
  synth::WriteSyntheticSequence(o, dir / "seq", testing::QuietProgress());
  const io::SequenceReader reader = io::SequenceReader::Open(dir / "seq");
  RunOptions options;
  options.pipeline.labels = ScenePipelineOptions::Labels::kGiven;
  options.pipeline.scene.meshing.tsdf.max_depth_m = 8.0;
  options.snapshot_every = 10;
  options.config_text = "labels: gt\n";
  const RunResult r = RunSequence(reader, nullptr, options, dir / "out",
                                  testing::QuietProgress());
  EXPECT_EQ(r.frames, 40u);
  EXPECT_EQ(r.skipped_frames, 0u);
  std::map<std::string, int> per_class;
  for (const auto& object : r.scene.objects_json) {
    if (object["kind"] == "object") {
      ++per_class[object["class"].get<std::string>()];
    }
  }
  for (const char* cls : {"sofa", "shelf", "table", "chair", "plant"}) {
    EXPECT_EQ(per_class[cls], 1) << cls;
  }
  EXPECT_EQ(per_class.count("person"), 0u);
  // The objects' meshes lie on the ground-truth surfaces: mean cloud-to-cloud
  // distance under half a TSDF voxel (10 mm; 5.7 mm measured) on noise-free
  // depth, ground truth sampled every 10 mm.
  const io::PlyData surface = io::ReadPly(dir / "seq/gt/surface_points.ply");
  std::vector<Eigen::Vector3f> mesh_points;
  for (const auto& object : r.scene.objects_json) {
    if (object["kind"] != "object") continue;
    const io::PlyData m =
        io::ReadPly(dir / "out" / object["ply"].get<std::string>());
    mesh_points.insert(mesh_points.end(), m.points.begin(), m.points.end());
  }
  const eval::DistanceStats c2c =
      eval::Summarize(eval::CloudToCloudDistances(mesh_points, surface.points));
  EXPECT_LT(c2c.mean_m, 0.01) << "median " << c2c.median_m;
  std::printf("mesh to ground truth: mean %.1f mm, median %.1f mm\n",
              1000 * c2c.mean_m, 1000 * c2c.median_m);
  const auto gt = io::ReadMotFile(dir / "seq/gt/people/gt.txt");
  std::set<int> gt_ids;
  for (const auto& b : gt) gt_ids.insert(b.id);
  const auto tracks = io::ReadMotFile(dir / "out/tracks.txt");
  std::set<int> run_ids;
  for (const auto& b : tracks) run_ids.insert(b.id);
  EXPECT_EQ(run_ids, gt_ids);
  EXPECT_EQ(r.scene.people, gt_ids.size());
  // Each tracked box lies on the ground truth's box of the same id.
  std::map<std::pair<int, int>, io::MotBox> gt_boxes;
  for (const auto& b : gt) gt_boxes[{b.frame, b.id}] = b;
  size_t matched = 0;
  for (const auto& b : tracks) {
    const auto it = gt_boxes.find({b.frame, b.id});
    if (it == gt_boxes.end()) continue;
    ++matched;
    EXPECT_NEAR(b.left, it->second.left, 2.0);
    EXPECT_NEAR(b.width, it->second.width, 3.0);
  }
  EXPECT_GT(matched, 0.8 * tracks.size());
  // Outputs a user looks at.
  for (const char* file : {"scene.usda", "static.usda", "dynamic.usda",
                           "report.json", "run.yaml", "tracks.txt"}) {
    EXPECT_TRUE(fs::is_regular_file(dir / "out" / file)) << file;
  }
  size_t overlays = 0;
  for (const auto& e : fs::directory_iterator(dir / "out/overlay")) {
    overlays += e.is_regular_file();
  }
  EXPECT_EQ(overlays, 40u);
  const auto report =
      nlohmann::json::parse(ReadTextFile(dir / "out/report.json"));
  EXPECT_EQ(report["snapshots"], 3);
  EXPECT_GT(report["peak_rss_mb"].get<double>(), 1.0);
  const std::string dynamic = ReadTextFile(dir / "out/dynamic.usda");
  EXPECT_NE(dynamic.find("timeSamples"), std::string::npos);
  const auto usd = testing::ValidateUsd(dir / "out/scene.usda", dir.path());
  if (!usd) SEMREC_SKIP("tinyusdz (npm) or node missing: run scripts/setup");
  EXPECT_TRUE((*usd)["ok"].get<bool>()) << (*usd)["error"];
}

// Person pixels stay out of the static map even when the segmentation calls
// them something else: with a segmenter that labels people "chair", the
// tracked people's masks keep every chair point away from them; without the
// masks the people end up in the chairs.
TEST(SceneBuilder, TrackedPeopleStayOutOfTheStaticMap) {
  testing::TempDir dir;
  synth::SynthOptions o = SmallScene("people", 24);
  o.noise.max_depth_m = 8.0;
  synth::WriteSyntheticSequence(o, dir / "seq", testing::QuietProgress());
  const io::SequenceReader reader = io::SequenceReader::Open(dir / "seq");
  const auto source = fuse::SegmentationSource::Create("gt", reader);
  const PersonMapSource people("gt", reader);
  const uint16_t chair = *source->classes().FindByName("chair");
  SceneBuilderOptions options;
  options.meshing.tsdf.max_depth_m = 8.0;
  SceneBuilder with(source->classes(), options);
  SceneBuilder without(source->classes(), options);
  for (size_t i = 0; i < reader.size(); ++i) {
    const Frame frame = reader.Read(i);
    fuse::FrameLabels labels = source->Get(reader, i);
    const auto ids = people.Get(i);
    ASSERT_TRUE(ids.has_value());
    for (size_t p = 0; p < ids->NumPixels(); ++p) {
      if (ids->data()[p] == 0) continue;
      labels.semantic.data()[p] = chair;
      labels.instance.data()[p] = 900;  // one "chair" mask over the people
    }
    with.Add(frame, &labels, &*ids);
    without.Add(frame, &labels, nullptr);
  }
  with.Finish();
  without.Finish();
  // Person points (above the knees: feet stand on the floor) from the tracked
  // people; chair points near them.
  std::vector<Eigen::Vector3f> person_points;
  for (const auto& track : with.PeopleTracks()) {
    for (const auto& sample : track.samples) {
      for (const auto& p : sample.points_world) {
        if (p.z() > 0.5f) person_points.push_back(p);
      }
    }
  }
  ASSERT_GT(person_points.size(), 100u);
  const auto chair_points_near_people = [&](const SceneBuilder& b) {
    std::vector<Eigen::Vector3f> chair_points;
    for (const auto& s : b.fusion().segments()) {
      if (s.class_id != chair) continue;
      chair_points.insert(chair_points.end(), s.points.begin(), s.points.end());
    }
    if (chair_points.empty()) return size_t{0};
    const std::vector<double> d =
        eval::CloudToCloudDistances(chair_points, person_points);
    return static_cast<size_t>(
        std::count_if(d.begin(), d.end(), [](double x) { return x < 0.05; }));
  };
  EXPECT_EQ(chair_points_near_people(with), 0u);
  EXPECT_GT(chair_points_near_people(without), 50u);
}

// A corrupt or missing frame is skipped with its file named and counted;
// --strict stops there instead.
// report.json's timing: the main thread's parts add up to the run's wall
// time, no stage's thread CPU exceeds its wall time, and the integration
// thread's wall time holds fusion, volumes and overlays (which overlap the
// segmentation of the next frame and so are not part of the run's sum).
TEST(RunSequence, TimingAccountsForTheRunsWallTime) {
  testing::TempDir dir;
  synth::WriteSyntheticSequence(SmallScene("six-objects", 8), dir / "seq",
                                testing::QuietProgress());
  const io::SequenceReader reader = io::SequenceReader::Open(dir / "seq");
  RunOptions options;
  options.pipeline.labels = ScenePipelineOptions::Labels::kGiven;
  options.config_text = "labels: gt\n";
  const RunResult r = RunSequence(reader, nullptr, options, dir / "out",
                                  testing::QuietProgress());
  const nlohmann::json& t = r.report.timing;
  const double run = t.at("run_wall").get<double>();
  EXPECT_NEAR(run, r.seconds, 1e-9);
  const nlohmann::json& main = t.at("main_thread");
  double parts = 0.0;
  for (const char* part : {"setup", "waiting_for_frames", "segment_and_track",
                           "waiting_for_integration", "finish_and_write"}) {
    const double seconds = main.at(part).get<double>();
    EXPECT_GE(seconds, 0.0) << part;
    parts += seconds;
  }
  EXPECT_NEAR(main.at("other").get<double>(), run - parts, 1e-9);
  EXPECT_GE(run - parts, -1e-6) << "parts measured on one thread overlap";
  EXPECT_LT(run - parts, 0.25 * run) << "the main thread's time is unaccounted";
  for (const auto& [stage, time] : t.at("stages").items()) {
    EXPECT_LE(time.at("cpu").get<double>(),
              time.at("wall").get<double>() * 1.05 + 0.01)
        << stage;
  }
  const nlohmann::json& stages = t.at("stages");
  // The overlay is drawn beside fuse and volumes: within the integration
  // thread's time, not after it.
  const double integration =
      t.at("integration_thread").at("wall").get<double>();
  EXPECT_GE(integration + 1e-6,
            stages.at("fuse").at("wall").get<double>() +
                stages.at("volumes").at("wall").get<double>());
  EXPECT_GE(integration + 1e-6, stages.at("overlay").at("wall").get<double>());
  EXPECT_GT(stages.at("volumes").at("wall").get<double>(), 0.0);
  EXPECT_GE(t.at("process_cpu").get<double>(), main.at("cpu").get<double>());
}

TEST(RunSequence, CorruptFramesAreSkippedAndCounted) {
  testing::TempDir dir;
  synth::SynthOptions o = SmallScene("six-objects", 6);
  synth::WriteSyntheticSequence(o, dir / "seq", testing::QuietProgress());
  const io::SequenceReader reader = io::SequenceReader::Open(dir / "seq");
  const fs::path broken = reader.index().frames[2].depth_path;
  testing::WriteText(broken, "not a png");
  fs::remove(reader.index().frames[4].color_path);
  RunOptions options;
  options.pipeline.labels = ScenePipelineOptions::Labels::kGiven;
  options.config_text = "labels: gt\n";
  const RunResult r = RunSequence(reader, nullptr, options, dir / "out",
                                  testing::QuietProgress());
  EXPECT_EQ(r.skipped_frames, 2u);
  const auto& skipped = r.report.skipped_frames;
  ASSERT_EQ(skipped.size(), 2u);
  EXPECT_EQ(skipped[0].frame, 2u);
  EXPECT_NE(skipped[0].reason.find(broken.filename().string()),
            std::string::npos);
  EXPECT_EQ(skipped[1].frame, 4u);
  // report.json is the report, read back field for field.
  const RunReport read = ReadRunReport(dir / "out" / "report.json");
  EXPECT_EQ(ToJson(read), ToJson(r.report));
  EXPECT_EQ(read.skipped_frames.size(), 2u);
  EXPECT_GT(r.scene.objects, 3u);
  options.strict = true;
  EXPECT_THROW(RunSequence(reader, nullptr, options, dir / "strict",
                           testing::QuietProgress()),
               FileError);
}

// Runs `options` into `out` as a run interrupted after `frames` frames (a run
// on a shorter sequence is refused as another sequence, so the checkpoint is
// cut back instead, and the final outputs removed), then resumes it;
// options->resume is set.
RunResult InterruptAndResume(const io::SequenceReader& reader,
                             RunOptions* options, const fs::path& out,
                             size_t frames) {
  RunSequence(reader, nullptr, *options, out, testing::QuietProgress());
  CheckpointStore(out / "checkpoint").Commit(frames);
  fs::remove(out / "scene.usda");
  fs::remove(out / "poses.txt");
  options->resume = true;
  return RunSequence(reader, nullptr, *options, out, testing::QuietProgress());
}

// A resumed run ends with the same scene as one that was not interrupted; a
// checkpoint of other options is refused.
TEST(RunSequence, ResumeGivesTheSameScene) {
  testing::TempDir dir;
  synth::SynthOptions o = SmallScene("six-objects", 12);
  o.write_noisy_labels = true;
  synth::WriteSyntheticSequence(o, dir / "seq", testing::QuietProgress());
  const io::SequenceReader reader = io::SequenceReader::Open(dir / "seq");
  RunOptions options;
  options.pipeline.labels = ScenePipelineOptions::Labels::kGiven;
  options.given_labels =
      fuse::LabelSpec::Parse((dir / "seq/labels_noisy").string());
  options.checkpoint_every = 4;
  options.config_text = "labels: noisy\n";
  RunSequence(reader, nullptr, options, dir / "clean",
              testing::QuietProgress());
  // Interrupted: the first 8 frames only.
  const RunResult resumed =
      InterruptAndResume(reader, &options, dir / "cut", 8);
  EXPECT_EQ(resumed.resumed_frames, 8u);
  EXPECT_EQ(ReadTextFile(dir / "cut/static.usda"),
            ReadTextFile(dir / "clean/static.usda"));
  // Other options: refused, saying so.
  options.config_text = "labels: noisy\nalpha: 0.3\n";
  try {
    RunSequence(reader, nullptr, options, dir / "cut",
                testing::QuietProgress());
    FAIL() << "a checkpoint of other options was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("different set of options"),
              std::string::npos)
        << e.what();
  }
  // No checkpoint at all.
  EXPECT_THROW(RunSequence(reader, nullptr, options, dir / "none",
                           testing::QuietProgress()),
               IoError);
}

// With estimated poses the replayed frames are tracked again: the resumed
// run writes the uninterrupted run's poses and scene. Dynamic classes are
// masked like people.
TEST(RunSequence, EstimatedPosesResumeAndLeaveDynamicClassesOut) {
  testing::TempDir dir;
  synth::WriteSyntheticSequence(SmallScene("six-objects", 8), dir / "seq",
                                testing::QuietProgress());
  const io::SequenceReader reader = io::SequenceReader::Open(dir / "seq");
  RunOptions options;
  options.pipeline.labels = ScenePipelineOptions::Labels::kGiven;
  options.poses = RunOptions::Poses::kEstimate;
  options.checkpoint_every = 4;
  options.config_text = "labels: gt\nposes: estimate\n";
  const RunResult clean = RunSequence(reader, nullptr, options, dir / "clean",
                                      testing::QuietProgress());
  EXPECT_EQ(clean.report.poses.source, "estimated");
  const RunResult resumed =
      InterruptAndResume(reader, &options, dir / "cut", 4);
  EXPECT_EQ(resumed.resumed_frames, 4u);
  EXPECT_EQ(ReadTextFile(dir / "cut/poses.txt"),
            ReadTextFile(dir / "clean/poses.txt"));
  EXPECT_EQ(ReadTextFile(dir / "cut/static.usda"),
            ReadTextFile(dir / "clean/static.usda"));
  // Dynamic classes are left out of tracking: the chair's pixels are masked
  // in every (segmented) frame; a class the label set lacks is refused.
  options.resume = false;
  options.dynamic_classes = {"chair"};
  const RunResult dynamic = RunSequence(
      reader, nullptr, options, dir / "dynamic", testing::QuietProgress());
  ASSERT_EQ(dynamic.report.poses.frames.size(), 8u);
  for (const PoseFrameRecord& f : dynamic.report.poses.frames) {
    EXPECT_GT(f.masked_pixels, 0u) << "frame " << f.frame;
  }
  EXPECT_EQ(clean.report.poses.frames[0].masked_pixels, 0u);
  options.dynamic_classes = {"unicorn"};
  EXPECT_THROW(RunSequence(reader, nullptr, options, dir / "unicorn",
                           testing::QuietProgress()),
               InvalidArgument);
  options.dynamic_classes.clear();
  // Map guidance needs poses before the frame is segmented.
  options.pipeline.map_guidance = true;
  try {
    RunSequence(reader, nullptr, options, dir / "guided",
                testing::QuietProgress());
    FAIL() << "map guidance ran with estimated poses";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("estimated poses come after"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace semrec::pipeline

namespace semrec::pipeline {
namespace {

// With a stride, given boxes are looked up by the recording's frame numbers
// and the result keeps them: image k of every 2nd frame is frame 1 + 2k.
TEST(Checkpoint, RecordsTheLabelsWithTheirConfidence) {
  const semrec::testing::TempDir dir;
  const CheckpointStore store(dir.path() / "checkpoint");
  fs::create_directories(store.dir());
  ModelOutputs o;
  o.labels = fuse::FrameLabels{LabelMap(4, 2, 1, 2), LabelMap(4, 2, 1, 20),
                               "frame.png (map-guided)"};
  o.labels->map_objects = {{3, 17}};
  o.labels->confidence = {{1, 0.55f}, {2, 1.0f / 3.0f}};
  o.guidance = "partial";
  store.Record(0, {std::nullopt, o});
  const CheckpointFrame back = store.Load(0);
  ASSERT_TRUE(back.outputs && back.outputs->labels);
  const fuse::FrameLabels& l = *back.outputs->labels;
  EXPECT_EQ(l.confidence, o.labels->confidence);  // exact, floats included
  EXPECT_EQ(l.map_objects, o.labels->map_objects);
  EXPECT_EQ(l.instance.values(), o.labels->instance.values());
  EXPECT_EQ(back.outputs->guidance, "partial");
}

TEST(TrackImages, StrideKeepsTheRecordingsFrameNumbers) {
  testing::TempDir dir;
  std::vector<segment::SegmentInput> inputs;
  std::map<int, std::vector<track::Detection>> given;
  for (int frame = 1; frame <= 9; ++frame) {
    track::Detection d;
    d.box = {2.0 * frame, 20.0, 30.0, 60.0};  // moves 2 px per frame
    d.score = 0.9;
    given[frame].push_back(d);
    if ((frame - 1) % 2 != 0) continue;  // stride 2: frames 1, 3, 5, 7, 9
    ColorImage image(160, 120, 3);
    const std::string name = fmt::format("{:03}.png", frame);
    io::WritePng(dir / "images" / name, image);
    inputs.push_back({name, dir / "images" / name});
  }
  TrackImagesOptions options;
  options.people.masks = false;
  options.people.tracker = track::TrackerOptions::Improved();
  options.people.tracker.min_hits = 1;
  options.frame_step = 2;
  const infer::ModelRegistry registry;
  const TrackImagesResult r =
      TrackImages(registry, options, {}, inputs, &given, dir / "out",
                  testing::QuietProgress());
  ASSERT_EQ(r.boxes.size(), 5u);
  for (const io::MotBox& b : r.boxes) {
    EXPECT_EQ((b.frame - 1) % 2, 0) << b.frame;
    EXPECT_NEAR(b.left, 2.0 * b.frame, 1e-6) << b.frame;
  }
  EXPECT_EQ(r.tracks, 1u);
  EXPECT_TRUE(fs::is_regular_file(dir / "out/persons/005.png"));
}

}  // namespace
}  // namespace semrec::pipeline

namespace semrec::pipeline {
namespace {

// People prims follow the smoothed tracks: unlisted tracks go, frames the
// smoothing dropped go, gaps it filled get an interpolated position.
TEST(FollowTracks, KeepsListedFramesAndInterpolatesGaps) {
  usd::PersonTrack a;
  a.track_id = 1;
  for (size_t f : {0u, 1u, 4u}) {
    usd::PersonSample s;
    s.frame = f;
    s.centroid_world = Eigen::Vector3f(static_cast<float>(f), 0.0f, 1.0f);
    s.points_world = {s.centroid_world};
    a.samples.push_back(s);
  }
  usd::PersonTrack b = a;
  b.track_id = 2;
  const auto out = FollowTracks({a, b}, {{1, {1, 2, 3, 4}}});
  ASSERT_EQ(out.size(), 1u);
  ASSERT_EQ(out[0].track_id, 1u);
  ASSERT_EQ(out[0].samples.size(), 4u);  // frame 0 dropped, 2-3 filled
  EXPECT_EQ(out[0].samples[0].frame, 1u);
  EXPECT_EQ(out[0].samples[1].frame, 2u);
  EXPECT_NEAR(out[0].samples[1].centroid_world.x(), 2.0f, 1e-6);
  EXPECT_NEAR(out[0].samples[2].centroid_world.x(), 3.0f, 1e-6);
  EXPECT_TRUE(out[0].samples[1].points_world.empty());
  EXPECT_EQ(out[0].samples[3].points_world.size(), 1u);
}

}  // namespace
}  // namespace semrec::pipeline
