// Object detections as class evidence: the class map, matching detections to
// masks, the vote's rule, and the hybrid segmenter end to end on tiny models
// (tests/models/make_tiny_models.py: a detector that always reports one
// chair).
#include "semrec/segment/detector_votes.h"

#include <nlohmann/json.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/io/label_set_io.h"
#include "semrec/segment/hybrid_segmenter.h"
#include "semrec/segment/vote.h"
#include "semrec/testing/masks.h"
#include "semrec/testing/test_util.h"

namespace fs = std::filesystem;

namespace semrec::segment {
namespace {

using ::testing::HasSubstr;

using testing::RectMask;

ObjectDetection Detected(Box box, uint16_t class_id, float score) {
  ObjectDetection d;
  d.box = box;
  d.class_id = class_id;
  d.score = score;
  return d;
}

TEST(DetectorClassMap, ShippedMapsNameRealClasses) {
  const LabelSet coco = io::LoadLabelSet("coco80");
  for (const auto& [set, expected] :
       std::vector<std::pair<std::string, std::string>>{
           {"ade20k-top31", "sofa"}, {"ade20k", "sofa"}, {"voc21", "sofa"}}) {
    const LabelSet labels = io::LoadLabelSet(set);
    const fs::path file = DetectorClassMap::DefaultPath("coco80", set);
    ASSERT_TRUE(fs::exists(file)) << file;
    const DetectorClassMap map = DetectorClassMap::Load(file, coco, labels);
    const auto couch = map.Map(*coco.FindByName("couch"));
    ASSERT_TRUE(couch.has_value()) << set;
    EXPECT_EQ(labels.Get(*couch).name, expected);
    // Classes without a counterpart are left out.
    EXPECT_FALSE(map.Map(*coco.FindByName("toothbrush")).has_value());
  }
  // Aliases find the same file.
  EXPECT_EQ(DetectorClassMap::DefaultPath("coco", "ade20k_top31"),
            DetectorClassMap::DefaultPath("coco80", "ade20k-top31"));
}

TEST(DetectorClassMap, UnknownNamesAreErrorsNamingTheFile) {
  const LabelSet coco = io::LoadLabelSet("coco80");
  const LabelSet top31 = io::LoadLabelSet("ade20k-top31");
  const semrec::testing::TempDir dir;
  const fs::path bad_target = dir.path() / "bad_target.json";
  WriteTextFileAtomic(bad_target, R"({"couch": "settee"})");
  try {
    DetectorClassMap::Load(bad_target, coco, top31);
    FAIL() << "no error";
  } catch (const FormatError& e) {
    EXPECT_THAT(e.what(), HasSubstr("bad_target.json"));
    EXPECT_THAT(e.what(), HasSubstr("'settee' is not a class"));
  }
  const fs::path bad_source = dir.path() / "bad_source.json";
  WriteTextFileAtomic(bad_source, R"({"sofa": "sofa"})");
  EXPECT_THROW(DetectorClassMap::Load(bad_source, coco, top31), FormatError);
  const fs::path not_object = dir.path() / "list.json";
  WriteTextFileAtomic(not_object, R"(["couch"])");
  EXPECT_THROW(DetectorClassMap::Load(not_object, coco, top31), FormatError);
}

TEST(ObjectEvidence, MapDetectionsKeepsMappedClassesAboveTheScoreClipped) {
  const LabelSet coco = io::LoadLabelSet("coco80");
  const LabelSet top31 = io::LoadLabelSet("ade20k-top31");
  const DetectorClassMap map = DetectorClassMap::Load(
      DetectorClassMap::DefaultPath("coco80", "ade20k-top31"), coco, top31);
  const auto det = [&](const char* name, double score, detect::Box box) {
    detect::LabeledDetection d;
    d.class_id = *coco.FindByName(name);
    d.score = score;
    d.box = box;
    return d;
  };
  const auto mapped = MapDetections(
      {det("chair", 0.8, {-10, 5, 50, 40}),
       det("toothbrush", 0.9, {0, 0, 5, 5}), det("couch", 0.2, {0, 0, 20, 20}),
       det("dining table", 0.5, {90, 90, 30, 30}),
       det("bed", 0.6, {120, 0, 10, 10})},
      map, 0.3f, 100, 100);
  ASSERT_EQ(mapped.size(), 2u);  // toothbrush unmapped, couch too weak, bed
                                 // outside the image
  EXPECT_EQ(top31.Get(mapped[0].class_id).name, "chair");
  EXPECT_EQ(mapped[0].box.x0, 0);  // clipped
  EXPECT_EQ(mapped[0].box.x1, 40);
  EXPECT_FLOAT_EQ(mapped[0].score, 0.8f);
  EXPECT_EQ(top31.Get(mapped[1].class_id).name, "table");
  EXPECT_EQ(mapped[1].box.x1, 100);
}

TEST(ObjectEvidence, MatchesPartsAndAddsUnmatchedGoodMasks) {
  const int w = 100, h = 100;
  ObjectDetectorOptions options;
  options.model = "tiny_yolox";
  // Generated: a chair split into a back (large) and seat (small, inside
  // the chair's box mask), and an unrelated wall.
  std::vector<Mask> masks = {RectMask(w, h, {0, 0, 100, 30}),
                             RectMask(w, h, {20, 40, 50, 70}),
                             RectMask(w, h, {22, 72, 48, 80})};
  const std::vector<ObjectDetection> detections = {
      Detected({20, 40, 50, 80}, 20, 0.8f),  // matches mask 1 (IoU 0.75)
      Detected({60, 40, 90, 90}, 16, 0.6f),  // no mask: adds its own
      Detected({60, 0, 70, 10}, 16, 0.9f)};  // no mask, poor one: dropped
  std::vector<Mask> detection_masks = {RectMask(w, h, {20, 40, 50, 80}),
                                       RectMask(w, h, {60, 40, 90, 90}, 0.95f),
                                       RectMask(w, h, {60, 0, 70, 10}, 0.5f)};
  const ObjectEvidence e =
      AttachDetections(masks, detections, detection_masks, options);
  EXPECT_EQ(e.matched, 1);
  EXPECT_EQ(e.added, 1);
  EXPECT_EQ(e.parts, 1);  // the seat, inside the chair's mask
  ASSERT_EQ(e.masks.size(), 4u);
  // Sorted by area: wall 3000, added table 1500, chair back 900, seat 208.
  EXPECT_EQ(e.masks[0].area, 3000);
  EXPECT_EQ(e.masks[1].area, 1500);
  EXPECT_EQ(e.detection, (std::vector<int>{-1, 1, 0, -1}));
  EXPECT_EQ(e.part_of, (std::vector<int>{-1, -1, -1, 0}));
  EXPECT_TRUE(e.evidence[0].empty());
  ASSERT_EQ(e.evidence[1].weights.size(), 1u);
  EXPECT_EQ(e.evidence[1].weights[0].class_id, 16);
  EXPECT_FLOAT_EQ(e.evidence[1].weights[0].weight, 0.6f);
  EXPECT_FLOAT_EQ(e.evidence[1].stuff_scale, 0.4f);
  EXPECT_FLOAT_EQ(e.evidence[2].weights[0].weight, 0.8f);
  // The seat lies wholly inside: the full score as a part.
  ASSERT_EQ(e.evidence[3].weights.size(), 1u);
  EXPECT_EQ(e.evidence[3].weights[0].class_id, 20);
  EXPECT_NEAR(e.evidence[3].weights[0].weight, 0.8f, 1e-6);
  // Stuff yields only in masks shaped like the object, not in parts (the
  // road under a car its box mask took in).
  EXPECT_FLOAT_EQ(e.evidence[2].stuff_scale, 0.2f);
  EXPECT_FLOAT_EQ(e.evidence[3].stuff_scale, 1.0f);

  // Without parts, stuff yielding and added masks: only the match remains.
  options.part_containment = 0;
  options.stuff_yields = false;
  options.min_predicted_iou = 2;
  const ObjectEvidence plain =
      AttachDetections(masks, detections, detection_masks, options);
  EXPECT_EQ(plain.masks.size(), 3u);
  EXPECT_EQ(plain.parts + plain.added, 0);
  EXPECT_FLOAT_EQ(plain.evidence[1].stuff_scale, 1.0f);
  EXPECT_THROW(AttachDetections(masks, detections, {}, options),
               InvalidArgument);
}

// A mask generator cuts a chair into back, seat and legs in most views, the
// same way each time, so views that agree still show three objects: the
// detection's masks that voted chair become one instance; a cup on the chair
// (inside its mask, voted cup) and the wall stay apart.
TEST(ObjectEvidence, PartsOfADetectedObjectBecomeOneInstance) {
  const int w = 100, h = 100;
  ObjectDetectorOptions options;
  options.model = "tiny_yolox";
  constexpr uint16_t kWall = 1, kChair = 20, kCup = 33;
  const std::vector<Mask> masks = {
      RectMask(w, h, {0, 0, 100, 20}),    // wall
      RectMask(w, h, {20, 20, 50, 50}),   // back
      RectMask(w, h, {20, 52, 50, 70}),   // seat
      RectMask(w, h, {22, 72, 48, 90}),   // legs
      RectMask(w, h, {30, 55, 36, 61})};  // cup on the seat
  const std::vector<ObjectDetection> detections = {
      Detected({20, 20, 50, 90}, kChair, 0.8f)};
  // The box-prompted mask is poor (predicted IoU 0.5): not added, so only the
  // parts carry the object.
  const ObjectEvidence e = AttachDetections(
      masks, detections, {RectMask(w, h, {20, 20, 50, 90}, 0.5f)}, options);
  ASSERT_EQ(e.masks.size(), 5u);
  EXPECT_EQ(e.part_of, (std::vector<int>{-1, 0, 0, 0, 0}));
  LabelMap semantic(w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      semantic(x, y) = y < 20                                     ? kWall
                       : (x >= 30 && x < 36 && y >= 55 && y < 61) ? kCup
                                                                  : kChair;
    }
  }
  VoteResult vote = Vote(semantic, e.masks, &e.evidence);
  ASSERT_EQ(vote.mask_labels,
            (std::vector<uint16_t>{kWall, kChair, kChair, kChair, kCup}));
  int joined = 0;
  const std::vector<uint16_t> instance =
      JoinDetectedParts(detections, e.detection, e.part_of, &vote, &joined);
  EXPECT_EQ(instance, (std::vector<uint16_t>{1, 2, 2, 2, 5}));
  EXPECT_EQ(joined, 2);
  EXPECT_EQ(vote.instance(25, 30), 2);  // back
  EXPECT_EQ(vote.instance(25, 60), 2);  // seat
  EXPECT_EQ(vote.instance(25, 80), 2);  // legs
  EXPECT_EQ(vote.instance(32, 57), 5);  // the cup stays itself
  EXPECT_EQ(vote.instance(50, 10), 1);  // the wall too
  // A part that voted another class than the detection's stays apart.
  VoteResult wall_seat = Vote(semantic, e.masks, &e.evidence);
  wall_seat.mask_labels[2] = kWall;
  EXPECT_EQ(JoinDetectedParts(detections, e.detection, e.part_of, &wall_seat,
                              &joined),
            (std::vector<uint16_t>{1, 2, 3, 2, 5}));
  EXPECT_EQ(joined, 1);
  EXPECT_THROW(
      JoinDetectedParts(detections, {}, e.part_of, &wall_seat, &joined),
      InvalidArgument);
}

TEST(ObjectEvidence, VoteCombinesPixelSharesWithDetections) {
  // A 10 x 10 mask: 70 pixels wall (1, stuff), 20 chair (20), 10 bed (8).
  const LabelSet top31 = io::LoadLabelSet("ade20k-top31");
  LabelMap semantic(10, 10);
  for (int y = 0; y < 10; ++y) {
    for (int x = 0; x < 10; ++x) semantic(x, y) = y < 7 ? 1 : (y < 9 ? 20 : 8);
  }
  const std::vector<Mask> masks = {RectMask(10, 10, {0, 0, 10, 10})};
  EXPECT_EQ(Vote(semantic, masks).mask_labels[0], 1);
  // A chair at 0.45 added only: 0.2 + 0.45 < 0.7 wall.
  std::vector<MaskEvidence> evidence(1);
  evidence[0].weights = {{20, 0.45f}};
  EXPECT_EQ(Vote(semantic, masks, &evidence, &top31).mask_labels[0], 1);
  // With wall yielding by 1 - 0.45: 0.385 < 0.65 -> chair; the agreement
  // stays the semantic share of the winner.
  evidence[0].stuff_scale = 0.55f;
  const VoteResult chair = Vote(semantic, masks, &evidence, &top31);
  EXPECT_EQ(chair.mask_labels[0], 20);
  EXPECT_FLOAT_EQ(chair.mask_agreement[0], 0.2f);
  // Confidence: the winner's part of all scores, 0.65 / (0.385 + 0.65 + 0.1).
  EXPECT_NEAR(chair.mask_confidence[0], 0.65 / 1.135, 1e-6);
  EXPECT_FLOAT_EQ(Vote(semantic, masks).mask_confidence[0], 0.7f);
  EXPECT_EQ(chair.semantic(5, 1), 20);
  // Stuff scaling needs the class table; a thing class never yields.
  EXPECT_EQ(Vote(semantic, masks, &evidence).mask_labels[0], 1);
  for (int y = 0; y < 7; ++y) {
    for (int x = 0; x < 10; ++x) semantic(x, y) = 8;  // bed, a thing
  }
  EXPECT_EQ(Vote(semantic, masks, &evidence, &top31).mask_labels[0], 8);
  // A detected class no pixel has can still win.
  evidence[0].weights = {{16, 0.7f}};
  evidence[0].stuff_scale = 1;
  EXPECT_EQ(Vote(semantic, masks, &evidence, &top31).mask_labels[0], 8);
  evidence[0].weights = {{16, 0.7f}, {16, 0.7f}};
  EXPECT_EQ(Vote(semantic, masks, &evidence, &top31).mask_labels[0], 16);
  std::vector<MaskEvidence> wrong(2);
  EXPECT_THROW(Vote(semantic, masks, &wrong), InvalidArgument);
}

TEST(ObjectEvidence, InstanceConfidenceOfMasksAndUnmaskedPixels) {
  // 10 x 2: a mask over columns 0..3 (class 3 and 5: 6 / 8 pixels class 3),
  // unmasked class 3 at columns 4..6 and class 5 at 7..9.
  LabelMap semantic(10, 2);
  Image<float> probability(10, 2);
  for (int y = 0; y < 2; ++y) {
    for (int x = 0; x < 10; ++x) {
      semantic(x, y) = (x < 3 || (x >= 4 && x < 7)) ? 3 : 5;
      probability(x, y) = x < 7 ? 0.5f : 0.9f;
    }
  }
  probability(4, 0) = 0.8f;
  const VoteResult vote = Vote(semantic, {RectMask(10, 2, {0, 0, 4, 2})});
  const std::map<uint16_t, float> c = InstanceConfidence(vote, probability);
  ASSERT_EQ(c.size(), 3u);
  EXPECT_FLOAT_EQ(c.at(1), 0.75f);                  // the mask's share
  EXPECT_NEAR(c.at(2), (0.8 + 5 * 0.5) / 6, 1e-6);  // unmasked class 3
  EXPECT_NEAR(c.at(3), 0.9, 1e-6);                  // unmasked class 5
  EXPECT_FLOAT_EQ(InstanceConfidence(vote, Image<float>()).at(2), 1.0f);
  EXPECT_THROW(InstanceConfidence(vote, Image<float>(3, 3)), InvalidArgument);
}

// End to end on tiny models: a rectangle the pixel classifier calls wall
// (palette colour 0 -> ADE-150 class 1) where the tiny detector reports a
// chair (its fixed box, 64x64 frame (8, 8)-(24, 32) x 5 = (40, 40)-(120, 160)
// in a 320 x 240 image).
class TinyHybrid : public ::testing::Test {
 protected:
  static ColorImage Scene() {
    const auto palette = nlohmann::json::parse(
        ReadTextFile(semrec::testing::TinyModelDir() / "tiny_palette150.json"));
    ColorImage rgb(320, 240, 3);
    for (int y = 0; y < 240; ++y) {
      for (int x = 0; x < 320; ++x) {
        const bool inside = x >= 40 && x < 120 && y >= 40 && y < 160;
        const int colour = inside ? 0 : 3;  // wall on floor (class 4)
        for (int c = 0; c < 3; ++c) {
          rgb(x, y, c) = palette[colour][c].get<uint8_t>();
        }
      }
    }
    return rgb;
  }
  static HybridSegmenterOptions Options() {
    infer::OnnxModelOptions runtime;
    runtime.model_dir = semrec::testing::TinyModelDir();
    runtime.intra_op_threads = 1;
    HybridSegmenterOptions o;
    o.semantic.model = "tiny_segformer";
    o.semantic.runtime = runtime;
    o.masks.model.encoder = "tiny_sam_encoder";
    o.masks.model.decoder = "tiny_sam_decoder";
    o.masks.model.runtime = runtime;
    o.masks.points_per_side = 8;
    o.objects.runtime = runtime;
    return o;
  }
  static uint16_t ClassAt(HybridSegmenterOptions options) {
    const auto registry = infer::ModelRegistry::Load(
        semrec::testing::TinyModelDir() / "registry.yaml");
    HybridSegmenter segmenter(registry, options);
    const HybridResult r = segmenter.Segment(Scene());
    return r.vote.semantic(80, 100);
  }
};

TEST_F(TinyHybrid, ADetectedChairOverridesTheWallTheClassifierSaw) {
  const LabelSet ade = io::LoadLabelSet("ade20k");
  HybridSegmenterOptions options = Options();
  EXPECT_EQ(ade.Get(ClassAt(options)).name, "wall");  // detector off
  options.objects.model = "tiny_yolox";
  const auto registry = infer::ModelRegistry::Load(
      semrec::testing::TinyModelDir() / "registry.yaml");
  HybridSegmenter segmenter(registry, options);
  ASSERT_TRUE(segmenter.detects_objects());
  const HybridResult r = segmenter.Segment(Scene());
  ASSERT_EQ(r.detections.size(), 1u);
  EXPECT_EQ(ade.Get(r.detections[0].class_id).name, "chair");
  EXPECT_NEAR(r.detections[0].score, 0.9, 1e-6);
  EXPECT_EQ(r.detections[0].box.x0, 40);
  EXPECT_EQ(r.detections[0].box.y1, 160);
  EXPECT_EQ(r.detections_matched, 1);
  // Unanimous wall pixels scaled by 1 - 0.9 lose to 0.9 chair.
  EXPECT_EQ(ade.Get(r.vote.semantic(80, 100)).name, "chair");
  EXPECT_EQ(ade.Get(r.vote.semantic(200, 200)).name, "floor");
  // Given detections replace the detector (shared with people tracking):
  // none given, none used.
  const std::vector<detect::LabeledDetection> none;
  EXPECT_EQ(
      ade.Get(segmenter.Segment(Scene(), &none).vote.semantic(80, 100)).name,
      "wall");
  // Only the added weight: 0.9 < 1.0 wall.
  options.objects.stuff_yields = false;
  EXPECT_EQ(ade.Get(ClassAt(options)).name, "wall");
  options.objects.weight = 2;
  EXPECT_EQ(ade.Get(ClassAt(options)).name, "chair");
}

TEST_F(TinyHybrid, DetectorNeedsMasksAndAClassMap) {
  const auto registry = infer::ModelRegistry::Load(
      semrec::testing::TinyModelDir() / "registry.yaml");
  HybridSegmenterOptions options = Options();
  options.objects.model = "tiny_yolox";
  options.use_masks = false;
  EXPECT_THROW(HybridSegmenter(registry, options), InvalidArgument);
  options = Options();
  options.objects.model = "tiny_yolox";
  options.objects.class_map = "/nonexistent/map.json";
  try {
    HybridSegmenter segmenter(registry, options);
    FAIL() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("/nonexistent/map.json"));
  }
  options.objects.class_map.clear();
  options.objects.weight = -1;
  EXPECT_THROW(HybridSegmenter(registry, options), InvalidArgument);
}

}  // namespace
}  // namespace semrec::segment
