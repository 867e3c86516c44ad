#include "semrec/fuse/fusion.h"

#include <map>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/fuse/fuse_sequence.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/synth/generator.h"
#include "semrec/testing/small_scene.h"
#include "semrec/testing/test_util.h"

namespace fs = std::filesystem;

namespace semrec::fuse {
namespace {

// A box surface sampled with noise, as one frame would see it.
Cloud BoxSurface(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi,
                 std::mt19937& rng, int n, float noise) {
  std::uniform_real_distribution<float> u(0, 1);
  std::normal_distribution<float> g(0, noise);
  Cloud c;
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3f p =
        lo + (hi - lo).cwiseProduct(Eigen::Vector3f(u(rng), u(rng), u(rng)));
    const int axis = i % 3;
    p[axis] = (i / 3) % 2 ? lo[axis] : hi[axis];
    c.push_back(p + Eigen::Vector3f(g(rng), g(rng), g(rng)));
  }
  return c;
}

std::vector<std::vector<FrameSegment>> RandomFrames(uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0, 4);
  struct Object {
    Eigen::Vector3f lo, hi;
    uint16_t cls;
  };
  std::vector<Object> objects;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3f lo(u(rng), u(rng), 0);
    objects.push_back(
        {lo, lo + Eigen::Vector3f(0.3f + u(rng) / 4, 0.3f + u(rng) / 4, 0.5f),
         static_cast<uint16_t>(1 + i % 3)});
  }
  std::vector<std::vector<FrameSegment>> frames(6);
  for (auto& frame : frames) {
    for (size_t o = 0; o < objects.size(); ++o) {
      if (rng() % 3 == 0) continue;  // not seen in this frame
      frame.push_back(
          {objects[o].cls, static_cast<uint16_t>(o + 1),
           BoxSurface(objects[o].lo, objects[o].hi, rng, 1500, 0.01f)});
    }
  }
  return frames;
}

void ExpectSameScene(const SceneFusion& a, const SceneFusion& b) {
  ASSERT_EQ(a.segments().size(), b.segments().size());
  for (size_t i = 0; i < a.segments().size(); ++i) {
    const SceneSegment& x = a.segments()[i];
    const SceneSegment& y = b.segments()[i];
    EXPECT_EQ(x.id, y.id);
    EXPECT_EQ(x.class_id, y.class_id);
    EXPECT_EQ(x.observations, y.observations);
    EXPECT_EQ(x.first_seen_frame, y.first_seen_frame);
    EXPECT_EQ(x.points, y.points) << "segment " << x.id;
  }
}

TEST(Fusion, FastAndBruteForceMakeIdenticalDecisions) {
  for (uint32_t seed : {1u, 2u, 3u, 4u}) {
    for (const auto merge :
         {FusionOptions::Merge::kPaper, FusionOptions::Merge::kEvidence}) {
      for (bool gating : {true, false}) {
        FusionOptions fast_options, brute_options;
        fast_options.label_gating = brute_options.label_gating = gating;
        fast_options.merge = brute_options.merge = merge;
        brute_options.method = FusionOptions::Method::kBruteForce;
        SceneFusion fast(fast_options), brute(brute_options);
        const auto frames = RandomFrames(seed);
        for (size_t f = 0; f < frames.size(); ++f) {
          const FrameFusionStats sf = fast.Integrate(frames[f], f);
          const FrameFusionStats sb = brute.Integrate(frames[f], f);
          EXPECT_EQ(sf.merged_frame_segments, sb.merged_frame_segments);
          EXPECT_EQ(sf.distance_computations_ungated,
                    sb.distance_computations_ungated);
          EXPECT_EQ(sf.evidence_merges, sb.evidence_merges);
          EXPECT_EQ(sf.cross_class_matches, sb.cross_class_matches);
          if (merge == FusionOptions::Merge::kPaper) {
            // The paper's count (evidence adds cross-class comparisons).
            EXPECT_EQ(sb.distance_computations_done,
                      gating ? sb.distance_computations_gated
                             : sb.distance_computations_ungated);
          }
          EXPECT_LE(sf.distance_computations_done,
                    sb.distance_computations_done);
        }
        EXPECT_EQ(fast.Finish(), brute.Finish());
        ExpectSameScene(fast, brute);
        // Each object, seen over several frames, ends as one segment.
        EXPECT_LE(fast.segments().size(), 8u);
      }
    }
  }
}

TEST(Fusion, GatingKeepsTouchingObjectsOfDifferentClassesApart) {
  std::mt19937 rng(3);
  // Two coinciding surfaces of different classes (e.g. a monitor standing on a
  // table top).
  const Cloud top = BoxSurface({0, 0, 0.7f}, {1, 1, 0.75f}, rng, 3000, 0.003f);
  const Cloud base =
      BoxSurface({0.3f, 0.3f, 0.75f}, {0.6f, 0.6f, 0.77f}, rng, 3000, 0.003f);
  for (bool gating : {true, false}) {
    FusionOptions options;
    options.label_gating = gating;
    SceneFusion fusion(options);
    fusion.Integrate({{4, 1, top}}, 0);
    const FrameFusionStats stats = fusion.Integrate({{12, 2, base}}, 1);
    if (gating) {
      EXPECT_EQ(fusion.segments().size(), 2u);
      EXPECT_EQ(stats.distance_computations_gated, 0u);
      EXPECT_GT(stats.distance_computations_ungated, 0u);
    } else {
      EXPECT_EQ(fusion.segments().size(), 1u)
          << "without labels the two objects merge";
    }
  }
}

TEST(Fusion, OneFrameSegmentMatchingTwoSceneSegmentsMergesThem) {
  std::mt19937 rng(4);
  SceneFusion fusion;
  fusion.Integrate(
      {{1, 1, BoxSurface({0, 0, 0}, {0.5f, 1, 0.5f}, rng, 4000, 0.002f)},
       {1, 2, BoxSurface({2, 0, 0}, {2.5f, 1, 0.5f}, rng, 4000, 0.002f)}},
      0);
  ASSERT_EQ(fusion.segments().size(), 2u);
  // A later view sees both halves as one segment (same class): they become one,
  // id 1.
  Cloud both = BoxSurface({0, 0, 0}, {0.5f, 1, 0.5f}, rng, 4000, 0.002f);
  const Cloud right = BoxSurface({2, 0, 0}, {2.5f, 1, 0.5f}, rng, 4000, 0.002f);
  both.insert(both.end(), right.begin(), right.end());
  const FrameFusionStats stats = fusion.Integrate({{1, 1, both}}, 1);
  ASSERT_EQ(fusion.segments().size(), 1u);
  EXPECT_EQ(fusion.segments()[0].id, 1u);
  EXPECT_EQ(fusion.segments()[0].observations, 3u);
  EXPECT_EQ(fusion.segments()[0].first_seen_frame, 0u);
  EXPECT_EQ(fusion.segments()[0].last_seen_frame, 1u);
  EXPECT_EQ(stats.removed_by_merge, 1u);
}

// Map-guided labels: pixels the map's projection labelled join the object it
// named, even where a fresh segment of that class would not, and count as no
// vote and no sighting (the map seeing itself); a found segment of another
// class lying on the same points does vote.
TEST(Fusion, MapProjectedSegmentsJoinTheirObjectWithoutVoting) {
  std::mt19937 rng(5);
  SceneFusion fusion;  // evidence merging (the default)
  const Cloud table =
      BoxSurface({0, 0, 0.7f}, {1, 1, 0.75f}, rng, 3000, 0.002f);
  fusion.Integrate({{15, 1, table}}, 0);
  ASSERT_EQ(fusion.segments().size(), 1u);
  const uint32_t id = fusion.segments()[0].id;
  const auto votes = fusion.segments()[0].class_votes;
  // Frames 1-5 labelled by projection: the same surface, "table" by the map.
  for (size_t frame = 1; frame <= 5; ++frame) {
    FrameSegment projected{
        15, 1, BoxSurface({0, 0, 0.7f}, {1, 1, 0.75f}, rng, 3000, 0.002f)};
    projected.map_object = id;
    const FrameFusionStats stats = fusion.Integrate({projected}, frame);
    EXPECT_EQ(stats.assigned_ids[0], id);
    EXPECT_EQ(stats.compared_pairs, 0u);
  }
  ASSERT_EQ(fusion.segments().size(), 1u);
  const SceneSegment& s = fusion.segments()[0];
  EXPECT_EQ(s.class_votes, votes);
  EXPECT_EQ(s.frames_seen, std::vector<uint32_t>{0});
  EXPECT_EQ(s.observations, 6u);
  EXPECT_EQ(s.last_seen_frame, 5u);
  // A named object that is gone (here: never existed) is an ordinary segment.
  FrameSegment stale{
      15, 1, BoxSurface({0, 0, 0.7f}, {1, 1, 0.75f}, rng, 3000, 0.002f)};
  stale.map_object = 999;
  fusion.Integrate({stale}, 6);
  ASSERT_EQ(fusion.segments().size(), 1u);
  EXPECT_EQ(fusion.segments()[0].frames_seen, (std::vector<uint32_t>{0, 6}));
  EXPECT_GT(fusion.segments()[0].class_votes.at(15), votes.at(15));
}

TEST(Fusion, OptionsAreChecked) {
  FusionOptions o;
  o.alpha = 1.0;
  EXPECT_THROW(SceneFusion{o}, InvalidArgument);
  o = {};
  o.corr_voxel_size_m = 0;
  EXPECT_THROW(SceneFusion{o}, InvalidArgument);
}

// `semrec segment` writes each instance's confidence into masks/<stem>.json;
// `--labels DIR` reads it back, so fusion weighs the votes as `semrec run`
// with the models does. Folders without it weigh 1; a bad entry names the
// file.
TEST(SegmentationSource, LabelFoldersCarryTheSegmentersConfidence) {
  testing::TempDir dir;
  synth::WriteSyntheticSequence(testing::SmallScene("six-objects", 2),
                                dir / "seq", testing::QuietProgress());
  const io::SequenceReader reader = io::SequenceReader::Open(dir / "seq");
  const fs::path labels = dir / "labels";
  for (const char* layer : {"instance", "semantic"}) {
    fs::create_directories(labels / layer);
    for (size_t i = 0; i < 2; ++i) {
      const fs::path name = reader.index().frames[i].depth_path.filename();
      fs::copy_file(reader.index().frames[i].layers.at(layer),
                    labels / layer / name);
    }
  }
  fs::copy_file(dir / "seq/gt/classes.json", labels / "classes.json");
  fs::create_directories(labels / "masks");
  const std::string stem = reader.index().frames[0].depth_path.stem().string();
  testing::WriteText(labels / "masks" / (stem + ".json"),
                     R"({"instance_confidence": {"3": 0.25, "7": 1}})");
  const auto source = SegmentationSource::Create(labels.string(), reader);
  const FrameLabels first = source->Get(reader, 0);
  EXPECT_EQ(first.confidence,
            (std::map<uint16_t, float>{{3, 0.25f}, {7, 1.0f}}));
  EXPECT_TRUE(source->Get(reader, 1).confidence.empty());
  testing::WriteText(labels / "masks" / (stem + ".json"),
                     R"({"instance_confidence": {"3": 1.5}})");
  try {
    source->Get(reader, 0);
    ADD_FAILURE() << "accepted a confidence of 1.5";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find(stem + ".json"), std::string::npos)
        << e.what();
  }
}

TEST(LabelSpec, ParsesWhatLabelsNameAndGivesTheTextBack) {
  using Kind = LabelSpec::Kind;
  for (const auto& [text, kind, value] :
       std::vector<std::tuple<std::string, Kind, std::string>>{
           {"models", Kind::kModels, ""},
           {"gt", Kind::kSequence, ""},
           {"single:chair", Kind::kSingleClass, "chair"},
           {"/runs/labels", Kind::kFolder, "/runs/labels"}}) {
    const LabelSpec spec = LabelSpec::Parse(text);
    EXPECT_EQ(spec.kind, kind) << text;
    EXPECT_EQ(spec.value, value) << text;
    EXPECT_EQ(spec.Text(), text);
    EXPECT_EQ(spec.given(), kind != Kind::kModels) << text;
  }
  EXPECT_THROW(LabelSpec::Parse(""), InvalidArgument);
  EXPECT_THROW(LabelSpec::Parse("single:"), InvalidArgument);
  testing::TempDir dir;
  synth::WriteSyntheticSequence(testing::SmallScene("six-objects", 1),
                                dir.path(), testing::QuietProgress());
  const io::SequenceReader reader = io::SequenceReader::Open(dir.path());
  EXPECT_THROW(SegmentationSource::Create(LabelSpec::Parse("models"), reader),
               InvalidArgument);
  EXPECT_THROW(SegmentationSource::Create("/no/such/labels", reader), IoError);
  EXPECT_EQ(
      SegmentationSource::Create("single:chair", reader)->classes().size(), 1u);
}

// On a synthetic sequence with ground-truth labels (a hand-held pace: 2 degrees
// of orbit per frame), every object ends as exactly one segment, no segment
// mixes objects, and fast and brute force agree on rendered data too.
TEST(Fusion, SyntheticSixObjectsEndAsOneSegmentEach) {
  testing::TempDir dir;
  const synth::SynthOptions o = testing::SmallScene("six-objects", 12);
  synth::WriteSyntheticSequence(o, dir.path(), testing::QuietProgress());
  const io::SequenceReader reader = io::SequenceReader::Open(dir.path());
  const auto source = SegmentationSource::Create("gt", reader);
  FusionOptions brute_options;
  brute_options.method = FusionOptions::Method::kBruteForce;
  SceneFusion fast, brute(brute_options);
  // Which GT instances (frame labels) went into which fused segment.
  std::vector<std::pair<uint16_t, uint32_t>> assignments;
  for (size_t i = 0; i < reader.size(); ++i) {
    const Frame frame = reader.Read(i);
    const FrameLabels labels = source->Get(reader, i);
    const auto segments =
        ExtractFrameSegments(frame, labels, source->classes(), {});
    const FrameFusionStats stats = fast.Integrate(segments, i);
    brute.Integrate(segments, i);
    for (size_t k = 0; k < segments.size(); ++k) {
      assignments.emplace_back(segments[k].source_label, stats.assigned_ids[k]);
    }
  }
  ExpectSameScene(fast, brute);
  std::map<uint16_t, std::set<uint32_t>> segments_of_object;
  std::map<uint32_t, std::set<uint16_t>> objects_of_segment;
  for (const auto& [gt, id] : assignments) {
    segments_of_object[gt].insert(fast.ResolveId(id));
    objects_of_segment[fast.ResolveId(id)].insert(gt);
  }
  synth::SceneOptions scene_options = o.scene;
  scene_options.seed = o.seed;
  const synth::Scene scene = synth::GenerateScene(scene_options);
  int objects_seen = 0;
  for (const synth::SceneObject& object : scene.objects) {
    if (object.structure || segments_of_object.count(object.instance_id) == 0) {
      continue;
    }
    ++objects_seen;
    EXPECT_EQ(segments_of_object[object.instance_id].size(), 1u)
        << object.name << " over-segmented";
  }
  EXPECT_GE(objects_seen, 4);
  // Objects stay apart; structure (the four walls, floor, ceiling) is one
  // segment per class.
  std::map<uint16_t, std::set<uint32_t>> structure_segments;  // class -> ids
  std::set<uint32_t> structure_ids;
  for (const synth::SceneObject& object : scene.objects) {
    if (!object.structure) continue;
    for (uint32_t id : segments_of_object[object.instance_id]) {
      structure_segments[object.class_id].insert(id);
      structure_ids.insert(id);
    }
  }
  EXPECT_GE(structure_segments.size(), 2u);  // walls and floor at least
  for (const auto& [cls, ids] : structure_segments) {
    EXPECT_EQ(ids.size(), 1u) << "structure class " << cls << " split";
  }
  for (const auto& [id, objects] : objects_of_segment) {
    if (structure_ids.count(id) != 0) continue;
    EXPECT_EQ(objects.size(), 1u)
        << "segment " << id << " merges different objects";
  }
  for (const SceneSegment& s : fast.segments()) {
    EXPECT_EQ(s.id, fast.ResolveId(s.id));
  }
}

TEST(Segments, SemanticZeroIsAClassOnlyWhenTheTableNamesIt) {
  Frame frame;
  frame.intrinsics = {4, 3, 2, 2, 1.5, 1};
  frame.depth = DepthImage(4, 3, 1, 1.0f);
  // Instance 1 voted 0 (6 of 8 pixels), instance 2 voted class 1.
  FrameLabels labels{LabelMap(4, 3, 1, 1), LabelMap(4, 3, 1, 0), "labels"};
  for (int u = 0; u < 4; ++u) labels.instance(u, 2) = 2;
  for (int u = 0; u < 4; ++u) labels.semantic(u, 2) = 1;
  labels.semantic(0, 0) = labels.semantic(1, 0) = 1;
  SegmentExtractionOptions options;
  options.min_points = 1;
  LabelSet ade("ade-like");
  ade.Add({1, "wall", {}});
  auto segments = ExtractFrameSegments(frame, labels, ade, options);
  ASSERT_EQ(segments.size(), 1u);
  EXPECT_EQ(segments[0].source_label, 2);
  LabelSet voc("voc-like");
  voc.Add({0, "background", {}});
  voc.Add({1, "chair", {}});
  segments = ExtractFrameSegments(frame, labels, voc, options);
  ASSERT_EQ(segments.size(), 2u);
  EXPECT_EQ(segments[0].source_label, 1);
  EXPECT_EQ(segments[0].class_id, 0);
  EXPECT_EQ(segments[0].points_world.size(), 8u);
  EXPECT_EQ(segments[1].class_id, 1);
}

TEST(Segments, FramesKeepTheirLabelsWhereTheyHaveNoDepth) {
  // 32 x 16 px: depth 2 m on the left half, none on the right; every pixel
  // class 5 (instance 4, confidence 0.6). The far view samples every 8th
  // pixel: cells 2, 3, 6, 7 (4 x 2 cells) lie on the right half.
  Frame frame;
  frame.intrinsics = {32, 16, 20, 20, 15.5, 7.5};
  frame.depth = DepthImage(32, 16, 1, 0.0f);
  for (int y = 0; y < 16; ++y) {
    for (int x = 0; x < 16; ++x) frame.depth(x, y) = 2.0f;
  }
  FrameLabels labels{LabelMap(32, 16, 1, 4), LabelMap(32, 16, 1, 5), "labels"};
  labels.confidence[4] = 0.6f;
  const FarView far = ObserveFrame(frame, labels, nullptr, 1).far;
  EXPECT_EQ(far.columns(), 4);
  EXPECT_EQ(far.rows(), 2);
  EXPECT_EQ(far.cells, (std::vector<uint32_t>{2, 3, 6, 7}));
  EXPECT_EQ(far.class_ids, (std::vector<uint16_t>{5, 5, 5, 5}));
  EXPECT_EQ(far.confidence, (std::vector<float>{0.6f, 0.6f, 0.6f, 0.6f}));
  EXPECT_FLOAT_EQ(far.max_ranged_depth_m, 2.0f);
  // Tracked people's pixels (cell 2's sample at (20, 4)) and unlabelled
  // pixels (cell 7's at (28, 12)) are left out.
  LabelMap people(32, 16, 1, 0);
  people(20, 4) = 1;
  labels.semantic(28, 12) = 0;
  EXPECT_EQ(ObserveFrame(frame, labels, &people, 1).far.cells,
            (std::vector<uint32_t>{3, 6}));
}

TEST(Segments, BadLabelsGiveClearErrors) {
  Frame frame;
  frame.intrinsics = {4, 3, 2, 2, 1.5, 1};
  frame.depth = DepthImage(4, 3, 1, 1.0f);
  LabelSet classes("test");
  classes.Add({1, "table", {}});
  FrameLabels labels{LabelMap(4, 3, 1, 7), LabelMap(4, 3, 1, 9),
                     "labels/000001.png"};
  SegmentExtractionOptions options;
  options.min_points = 1;
  try {
    ExtractFrameSegments(frame, labels, classes, options);
    FAIL();
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "labels/000001.png: semantic label 9 is not in the "
                  "class table"),
              std::string::npos)
        << e.what();
  }
  labels.semantic = LabelMap(5, 3, 1, 1);
  EXPECT_THROW(ExtractFrameSegments(frame, labels, classes, options),
               FormatError);
  // No valid depth: no segments, no error.
  labels.semantic = LabelMap(4, 3, 1, 1);
  frame.depth = DepthImage(4, 3, 1, 0.0f);
  EXPECT_TRUE(ExtractFrameSegments(frame, labels, classes, options).empty());
}

}  // namespace

// The confidence written with an object is its own class's share of the
// votes: the map may give a thing the class after structure (a chair most
// views called wall), whose share is not the winner's.
TEST(ClassConfidence, IsTheShareOfTheObjectsOwnClass) {
  SceneSegment s;
  s.class_id = 5;
  EXPECT_DOUBLE_EQ(ClassConfidence(s), 1.0);  // no votes: nothing says less
  s.class_votes = {{2, 72}, {5, 12}, {13, 9}, {15, 7}};
  EXPECT_DOUBLE_EQ(ClassConfidence(s), 0.12);
  s.class_id = 2;
  EXPECT_DOUBLE_EQ(ClassConfidence(s), 0.72);
  s.class_id = 9;  // a class no view gave
  EXPECT_DOUBLE_EQ(ClassConfidence(s), 0.0);
}

}  // namespace semrec::fuse
