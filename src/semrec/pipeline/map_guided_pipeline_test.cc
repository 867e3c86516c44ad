// Map-guided segmentation end to end on the tiny models that
// segment by colour: a synthetic RGB-D sequence whose every pixel's object is
// known, with an object that enters and one that is taken away.
#include <algorithm>
#include <map>
#include <set>
#include <tuple>
#include <vector>

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include "semrec/core/file_util.h"
#include "semrec/fuse/gravity.h"
#include "semrec/pipeline/map_guidance.h"
#include "semrec/pipeline/scene_pipeline.h"
#include "semrec/testing/test_util.h"

namespace semrec::pipeline {
namespace {

// Fronto-parallel rectangles in the world frame (x right, y down, z ahead),
// each a flat palette colour, present in frames [first, last].
struct Rect {
  int id;
  int colour;  // palette index; the tiny models' class is colour + 1
  float x0, x1, y0, y1, z;
  size_t first = 0, last = 1000;
};

constexpr int kWidth = 320, kHeight = 240;
constexpr int kWall = 0, kCabinet = 10, kTable = 15, kChair = 19;

std::vector<Rect> Scene() {
  return {{1, kWall, -5, 5, -5, 5, 3.0f},
          {2, kCabinet, -0.9f, -0.3f, -0.5f, 0.1f, 2.0f},
          {3, kTable, 0.2f, 0.8f, -0.4f, 0.3f, 2.2f, 0, 8},
          {4, kChair, -0.3f, 0.3f, 0.35f, 0.8f, 1.8f, 4}};
}

struct Rendered {
  Frame frame;
  Image<uint8_t> gt_id;
};

// Frame i: the camera looks along +z from x = 5 mm * i (no rotation).
Rendered Render(size_t i, const std::vector<std::array<uint8_t, 3>>& palette) {
  Rendered r;
  Frame& f = r.frame;
  f.index = i;
  f.timestamp_s = static_cast<double>(i) / 30.0;
  f.intrinsics.width = kWidth;
  f.intrinsics.height = kHeight;
  f.intrinsics.fx = f.intrinsics.fy = 262.5;
  f.intrinsics.cx = 160;
  f.intrinsics.cy = 120;
  const double camera_x = 0.005 * static_cast<double>(i);
  f.T_world_camera =
      Transform(Eigen::Matrix3d::Identity(), Eigen::Vector3d(camera_x, 0, 0));
  f.color = ColorImage(kWidth, kHeight, 3);
  f.depth = DepthImage(kWidth, kHeight);
  r.gt_id = Image<uint8_t>(kWidth, kHeight);
  f.color_path = "frame_" + std::to_string(i) + ".png";
  f.depth_path = "depth_" + std::to_string(i) + ".png";
  const std::vector<Rect> scene = Scene();
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      const double rx = (u + 0.5 - 160) / 262.5, ry = (v + 0.5 - 120) / 262.5;
      const Rect* nearest = nullptr;
      for (const Rect& rect : scene) {
        if (i < rect.first || i > rect.last) continue;
        const double x = camera_x + rx * rect.z, y = ry * rect.z;
        if (x < rect.x0 || x >= rect.x1 || y < rect.y0 || y >= rect.y1) {
          continue;
        }
        if (nearest == nullptr || rect.z < nearest->z) nearest = &rect;
      }
      if (nearest == nullptr) continue;  // (the wall fills every view)
      f.depth(u, v) = nearest->z;
      r.gt_id(u, v) = static_cast<uint8_t>(nearest->id);
      for (int c = 0; c < 3; ++c) {
        f.color(u, v, c) = palette[nearest->colour][c];
      }
    }
  }
  return r;
}

// The tiny models' colours (by class index) and registry.
std::vector<std::array<uint8_t, 3>> TinyPalette() {
  return nlohmann::json::parse(ReadTextFile(semrec::testing::TinyModelDir() /
                                            "tiny_palette150.json"))
      .get<std::vector<std::array<uint8_t, 3>>>();
}

ScenePipelineOptions GuidedOptions() {
  ScenePipelineOptions o;
  o.labels = ScenePipelineOptions::Labels::kModels;
  o.segmenter.semantic.model = "tiny_segformer";
  infer::OnnxModelOptions runtime;
  runtime.model_dir = semrec::testing::TinyModelDir();
  runtime.intra_op_threads = 1;
  o.segmenter.semantic.runtime = runtime;
  o.segmenter.masks.model.encoder = "tiny_sam_encoder";
  o.segmenter.masks.model.decoder = "tiny_sam_decoder";
  o.segmenter.masks.model.runtime = runtime;
  o.segmenter.masks.points_per_side = 16;
  o.track_people = false;
  o.overlays = false;
  o.scene.gravity = fuse::ParseGravity("none");
  o.map_guidance = true;
  o.guidance.refresh_every = 6;
  return o;
}

// Share of the pixels of object `gt` whose label is `class_id`, and the
// share the most common instance holds.
std::pair<double, double> Agreement(const fuse::FrameLabels& labels,
                                    const Image<uint8_t>& gt_id, int gt,
                                    int class_id) {
  size_t n = 0, same = 0;
  std::map<uint16_t, size_t> instances;
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      if (gt_id(u, v) != gt) continue;
      ++n;
      same += labels.semantic(u, v) == class_id ? 1 : 0;
      ++instances[labels.instance(u, v)];
    }
  }
  size_t top = 0;
  for (const auto& [instance, count] : instances) {
    if (instance != 0) top = std::max(top, count);
  }
  const double total = static_cast<double>(std::max<size_t>(n, 1));
  return {static_cast<double>(same) / total, static_cast<double>(top) / total};
}

// What the pipeline will see in frame 4: the map after frame 2, projected
// into frame 4, where the chair has just come in. Prompts may land on the
// chair (and the margin around it) only, and the known objects are explained
// with their own ids.
void CheckChairFrameProjection(const ScenePipeline& pipeline,
                               const Rendered& r) {
  // What the pipeline will see: the map after frame 2, projected into
  // frame 4, where the chair has just come in. Prompts may land on the
  // chair (and the margin around it) only.
  const fuse::ProjectedMap projected =
      fuse::ProjectMap(pipeline.scene().fusion().segments(), r.frame.intrinsics,
                       r.frame.T_world_camera, r.frame.depth);
  const GuidanceDecision d = DecideFrame(projected, r.frame.T_world_camera,
                                         Transform(), 1, MapGuidanceOptions());
  ASSERT_EQ(d.mode, FrameMode::kPartial);
  size_t chair = 0, chair_in_region = 0, others_in_region = 0;
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      const bool is_chair = r.gt_id(u, v) == 4;
      chair += is_chair ? 1 : 0;
      if (d.prompt_region(u, v) == 0) continue;
      (is_chair ? chair_in_region : others_in_region) += 1;
    }
  }
  EXPECT_EQ(chair_in_region, chair);
  // The margin only: a band of 8 pixels around the 59 x 66 chair.
  EXPECT_LT(others_in_region, 2 * 8 * (59 + 66 + 16) + 100);
  // The known objects are explained with their own ids: each GT object
  // maps (but for fringe objects of the tiny model's borders) onto one map
  // object, its own.
  std::map<int, std::map<uint32_t, size_t>> map_ids;
  std::map<int, size_t> explained;
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      if (projected.state(u, v) == fuse::ProjectedMap::kExplained) {
        ++map_ids[r.gt_id(u, v)][projected.object_id(u, v)];
        ++explained[r.gt_id(u, v)];
      }
    }
  }
  EXPECT_EQ(map_ids.count(4), 0u);
  std::set<uint32_t> dominant;
  for (const int known : {1, 2, 3}) {
    size_t top = 0;
    uint32_t top_id = 0;
    for (const auto& [id, n] : map_ids[known]) {
      if (n > top) std::tie(top, top_id) = std::tie(n, id);
    }
    EXPECT_GT(static_cast<double>(top), 0.95 * explained[known]) << known;
    dominant.insert(top_id);
  }
  EXPECT_EQ(dominant.size(), 3u);
}

class MapGuidedPipeline : public ::testing::TestWithParam<bool> {};

// Param: prompt_on_disagreement (the tiny semantic branch agrees with the map
// but for blurred borders: nothing changes).
TEST_P(MapGuidedPipeline, SegmentsOnlyWhatTheMapCannotExplain) {
  ASSERT_FALSE(semrec::testing::TinyModelDir().empty());
  const auto palette = TinyPalette();
  const infer::ModelRegistry registry =
      infer::ModelRegistry::Load(semrec::testing::TinyRegistryFile());
  ScenePipelineOptions options = GuidedOptions();
  options.guidance.prompt_on_disagreement = GetParam();
  ScenePipeline pipeline(&registry, nullptr, options);

  std::vector<std::string> modes;
  std::vector<size_t> prompts;
  std::vector<fuse::FrameLabels> labels;
  std::vector<Image<uint8_t>> gt;
  for (size_t i = 0; i < 12; ++i) {
    Rendered r = Render(i, palette);
    gt.push_back(r.gt_id);
    if (i == 4) CheckChairFrameProjection(pipeline, r);
    const size_t before = pipeline.guidance_counts().prompts_decoded;
    PipelineInput input;
    input.frame = std::move(r.frame);
    input.name = "frame.png";
    PipelineFrameResult result = pipeline.Process(input);
    ASSERT_TRUE(result.outputs.labels.has_value());
    modes.push_back(result.outputs.guidance);
    prompts.push_back(pipeline.guidance_counts().prompts_decoded - before);
    labels.push_back(std::move(*result.outputs.labels));
  }
  pipeline.Finish();

  // Frame 1 has no map yet (frame i sees the map after frame i - 2); frame 7
  // is the refresh; the chair (frame 4) and the wall behind the table taken
  // away (frame 9) are new content until the map holds them.
  const std::vector<std::string> expected = {
      "full",       "full",    "projection", "projection",
      "partial",    "partial", "projection", "full",
      "projection", "partial", "partial",    "projection"};
  EXPECT_EQ(modes, expected);
  const GuidanceCounts& counts = pipeline.guidance_counts();
  EXPECT_EQ(counts.full, 3u);
  EXPECT_EQ(counts.partial, 4u);
  EXPECT_EQ(counts.projection, 5u);
  EXPECT_EQ(counts.encoder_calls, 3u + 4u);
  EXPECT_EQ(counts.disagreement, 0u);
  for (size_t i = 0; i < modes.size(); ++i) {
    if (modes[i] == "projection") {
      EXPECT_EQ(prompts[i], 0u) << i;
    }
    if (modes[i] == "partial") {
      EXPECT_LT(prompts[i], prompts[0] / 2) << i;
    }
  }

  // Frames labelled by projection agree with the ground truth, one instance
  // per object (but for fringes of the tiny model's blurred borders).
  for (const size_t i : {2u, 3u, 6u, 8u}) {
    for (const auto& [id, colour] :
         std::vector<std::pair<int, int>>{{2, kCabinet}, {3, kTable}}) {
      const auto [agree, one_instance] =
          Agreement(labels[i], gt[i], id, colour + 1);
      EXPECT_GT(agree, 0.95) << "frame " << i << " object " << id;
      EXPECT_GT(one_instance, 0.95) << "frame " << i << " object " << id;
    }
  }
  // The chair is found when it enters (fresh masks, voted; the tiny semantic
  // branch blurs its one-pixel rim) ...
  EXPECT_GT(Agreement(labels[4], gt[4], 4, kChair + 1).first, 0.9);
  // ... and where the table was, the wall now shows: not labelled table.
  EXPECT_GT(Agreement(labels[9], gt[9], 1, kWall + 1).first, 0.95);
  size_t table_pixels = 0;
  for (const uint16_t c : labels[9].semantic.values()) {
    table_pixels += c == kTable + 1 ? 1 : 0;
  }
  EXPECT_EQ(table_pixels, 0u);

  // The scene holds each object once, the chair included.
  std::map<uint16_t, int> per_class;
  for (const fuse::SceneSegment& s : pipeline.scene().fusion().segments()) {
    ++per_class[s.class_id];
    // Frames labelled by the map are no sightings of what it already held:
    // the cabinet was seen in the full frames only.
    if (s.class_id == kCabinet + 1) {
      EXPECT_EQ(s.frames_seen, (std::vector<uint32_t>{0, 1, 7}));
    }
  }
  EXPECT_EQ(per_class[kCabinet + 1], 1);
  EXPECT_EQ(per_class[kTable + 1], 1);
  EXPECT_EQ(per_class[kChair + 1], 1);
}

INSTANTIATE_TEST_SUITE_P(Disagreement, MapGuidedPipeline, ::testing::Bool());

// A resumed run replays the first frames' recorded outputs (no model runs):
// the guidance state (last full frame, frames since) and fusion's map objects
// come back with them, so the rest of the run decides and fuses as before.
TEST(MapGuidedReplay, ReplayedFramesRestoreTheGuidance) {
  ASSERT_FALSE(semrec::testing::TinyModelDir().empty());
  const auto palette = TinyPalette();
  const infer::ModelRegistry registry =
      infer::ModelRegistry::Load(semrec::testing::TinyRegistryFile());
  const auto run = [&](const std::vector<ModelOutputs>* recorded,
                       size_t replay_frames) {
    ScenePipeline pipeline(&registry, nullptr, GuidedOptions());
    std::vector<ModelOutputs> outputs;
    for (size_t i = 0; i < 12; ++i) {
      PipelineInput input;
      input.frame = Render(i, palette).frame;
      input.name = "frame.png";
      if (i < replay_frames) input.replay = (*recorded)[i];
      outputs.push_back(pipeline.Process(input).outputs);
    }
    pipeline.Finish();
    std::vector<std::pair<uint16_t, size_t>> objects;
    for (const fuse::SceneSegment& s : pipeline.scene().fusion().segments()) {
      objects.emplace_back(s.class_id, s.points.size());
    }
    return std::make_tuple(outputs, objects, pipeline.guidance_counts());
  };
  const auto [outputs, objects, counts] = run(nullptr, 0);
  // Resumed after frame 5 (frame 4 was partial, 5 too): frames 6.. decide as
  // before (6 projection, 7 the refresh, ...).
  const auto [outputs2, objects2, counts2] = run(&outputs, 6);
  ASSERT_EQ(outputs2.size(), outputs.size());
  for (size_t i = 0; i < outputs.size(); ++i) {
    EXPECT_EQ(outputs2[i].guidance, outputs[i].guidance) << i;
    ASSERT_TRUE(outputs2[i].labels.has_value());
    EXPECT_EQ(outputs2[i].labels->map_objects, outputs[i].labels->map_objects)
        << i;
    EXPECT_EQ(outputs2[i].labels->semantic.values(),
              outputs[i].labels->semantic.values())
        << i;
  }
  EXPECT_EQ(objects2, objects);
  EXPECT_EQ(counts2.full, counts.full);
  EXPECT_EQ(counts2.partial, counts.partial);
  EXPECT_EQ(counts2.projection, counts.projection);
}

// Object evidence and people tracking with the same detector run it once per
// frame, and the people come out exactly as with the tracker's own pass (the
// tiny detector always reports one chair; the "people" tracker here tracks
// chairs so that it has something to track).
TEST(ObjectDetectorPipeline, OneDetectorPassServesPeopleAndObjects) {
  ASSERT_FALSE(semrec::testing::TinyModelDir().empty());
  const auto palette = TinyPalette();
  const infer::ModelRegistry registry =
      infer::ModelRegistry::Load(semrec::testing::TinyRegistryFile());
  const auto run = [&](bool objects) {
    ScenePipelineOptions options = GuidedOptions();
    options.map_guidance = false;
    options.segment_every = 2;
    options.track_people = true;
    options.people.detector.model = "tiny_yolox";
    options.people.detector.classes = {57};  // COCO chair
    options.people.detector.runtime = options.segmenter.semantic.runtime;
    options.people.mask_model = options.segmenter.masks.model;
    options.people.tracker = track::TrackerOptions::Paper();
    if (objects) {
      options.segmenter.objects.model = "tiny_yolox";
      options.segmenter.objects.runtime = options.segmenter.semantic.runtime;
    }
    ScenePipeline pipeline(&registry, nullptr, options);
    for (size_t i = 0; i < 4; ++i) {
      PipelineInput input;
      input.frame = Render(i, palette).frame;
      input.name = "frame.png";
      pipeline.Process(input);
    }
    pipeline.Finish();
    return std::make_pair(pipeline.Tracks(), pipeline.object_counts());
  };
  const auto [tracks, counts] = run(false);
  const auto [shared_tracks, shared_counts] = run(true);
  ASSERT_EQ(tracks.size(), 4u);  // one box per frame
  ASSERT_EQ(shared_tracks.size(), tracks.size());
  for (size_t i = 0; i < tracks.size(); ++i) {
    EXPECT_EQ(shared_tracks[i].frame, tracks[i].frame);
    EXPECT_EQ(shared_tracks[i].id, tracks[i].id);
    EXPECT_DOUBLE_EQ(shared_tracks[i].left, tracks[i].left);
    EXPECT_DOUBLE_EQ(shared_tracks[i].width, tracks[i].width);
  }
  EXPECT_EQ(counts.detections, 0u);
  // Frames 0 and 2 segmented, each with the one (chair) detection.
  EXPECT_EQ(shared_counts.shared_passes, 2u);
  EXPECT_EQ(shared_counts.detections, 2u);
  EXPECT_EQ(shared_counts.matched + shared_counts.added, 2u);
}

TEST(MapGuidedLabels, ComposedLabelsTakeTheMapWhereItExplains) {
  fuse::ProjectedMap projected;
  projected.state = Image<uint8_t>(4, 1, 1, fuse::ProjectedMap::kExplained);
  projected.object_id = Image<uint32_t>(4, 1);
  projected.class_id = LabelMap(4, 1);
  projected.object_id(0, 0) = 7;
  projected.class_id(0, 0) = 3;
  projected.object_id(1, 0) = 9;
  projected.class_id(1, 0) = 5;
  projected.state(2, 0) = fuse::ProjectedMap::kUnexplained;
  projected.state(3, 0) = fuse::ProjectedMap::kUnexplained;
  GuidanceDecision d;
  d.mode = FrameMode::kPartial;
  d.prompt_region = Image<uint8_t>(4, 1);
  d.prompt_region(1, 0) = 1;
  d.prompt_region(2, 0) = 1;
  segment::VoteResult fresh;
  fresh.instance = LabelMap(4, 1, 1, 2);
  fresh.semantic = LabelMap(4, 1, 1, 11);
  const fuse::FrameLabels l = ComposeFrameLabels(projected, d, &fresh, "f");
  // Explained: the map's classes, instances after the fresh ones (max 2).
  EXPECT_EQ(l.semantic(0, 0), 3);
  EXPECT_EQ(l.instance(0, 0), 3);
  EXPECT_EQ(l.semantic(1, 0), 5);  // explained wins over the region
  EXPECT_EQ(l.instance(1, 0), 4);
  EXPECT_EQ(l.semantic(2, 0), 11);  // unexplained, in the region: fresh
  EXPECT_EQ(l.instance(2, 0), 2);
  EXPECT_EQ(l.semantic(3, 0), 0);  // unexplained, outside it: nothing
  EXPECT_EQ(l.instance(3, 0), 0);
  // Fusion learns which map object each projected instance is.
  EXPECT_EQ(l.map_objects, (std::map<uint16_t, uint32_t>{{3, 7}, {4, 9}}));
  // Projection only: the map alone.
  d.mode = FrameMode::kProjectionOnly;
  const fuse::FrameLabels p = ComposeFrameLabels(projected, d, nullptr, "f");
  EXPECT_EQ(p.instance(0, 0), 1);
  EXPECT_EQ(p.semantic(2, 0), 0);
  d.mode = FrameMode::kPartial;
  EXPECT_THROW(ComposeFrameLabels(projected, d, nullptr, "f"), InvalidArgument);
}

}  // namespace
}  // namespace semrec::pipeline
