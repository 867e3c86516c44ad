#include "semrec/eval/scene_metrics.h"

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/io/ply_io.h"
#include "semrec/testing/test_util.h"

namespace semrec::eval {
namespace {

constexpr int32_t kWall = 2, kTable = 4, kChair = 5;

// Ground truth on a line, 1 cm apart: a wall (structure, instance 0), two
// chairs (instances 1, 2) and a table (3), 100 points each.
struct Fixture {
  SceneGroundTruth gt;
  std::vector<Eigen::Vector3f> Points(int32_t instance, int32_t cls,
                                      int from = 0, int to = 100) const {
    std::vector<Eigen::Vector3f> out;
    int k = 0;
    for (size_t i = 0; i < gt.points.size(); ++i) {
      if (gt.instance[i] == instance && gt.semantic[i] == cls) {
        if (k >= from && k < to) out.push_back(gt.points[i]);
        ++k;
      }
    }
    return out;
  }
  Fixture() {
    const std::pair<int32_t, int32_t> parts[] = {
        {kWall, 0}, {kChair, 1}, {kChair, 2}, {kTable, 3}};
    float x = 0;
    for (const auto& [cls, instance] : parts) {
      for (int i = 0; i < 100; ++i, x += 0.01f) {
        gt.points.emplace_back(x, 0, 0);
        gt.semantic.push_back(cls);
        gt.instance.push_back(instance);
      }
      x += 1.0f;
    }
  }
};

SceneEvalOptions Tight() {
  SceneEvalOptions o;
  o.radius_m = 0.004;  // each point's own copy, not its neighbour
  return o;
}

const std::set<int32_t> kThings = {kTable, kChair};

TEST(SceneMetrics, ScanNetAveragePrecisionByHand) {
  EXPECT_DOUBLE_EQ(ScanNetAveragePrecision({true}, {0.9}, 0), 1.0);
  // A false positive scored below every true positive costs nothing...
  EXPECT_DOUBLE_EQ(ScanNetAveragePrecision({true, false}, {0.9, 0.8}, 0), 1.0);
  // ... above, it does: precision 1/2 at recall 1, then 0 (ScanNet's steps).
  EXPECT_DOUBLE_EQ(ScanNetAveragePrecision({true, false}, {0.8, 0.9}, 0), 0.25);
  // One of two objects found: recall 1/2.
  EXPECT_DOUBLE_EQ(ScanNetAveragePrecision({true}, {0.9}, 1), 0.5);
  EXPECT_DOUBLE_EQ(ScanNetAveragePrecision({}, {}, 2), 0.0);
}

TEST(SceneMetrics, OraclePredictionsScorePerfectly) {
  const Fixture f;
  const std::vector<PredictedObject> predicted = {
      {10, kWall, 5, f.Points(0, kWall)},
      {11, kChair, 4, f.Points(1, kChair)},
      {12, kChair, 3, f.Points(2, kChair)},
      {13, kTable, 2, f.Points(3, kTable)}};
  const SceneMetrics m = EvaluateScene(f.gt, predicted, kThings, Tight());
  EXPECT_EQ(m.gt_points, 400u);
  EXPECT_EQ(m.covered_points, 400u);
  EXPECT_DOUBLE_EQ(m.mean_iou, 1.0);
  EXPECT_DOUBLE_EQ(m.ap25, 1.0);
  EXPECT_DOUBLE_EQ(m.ap50, 1.0);
  EXPECT_DOUBLE_EQ(m.recall50, 1.0);
  EXPECT_DOUBLE_EQ(m.precision50, 1.0);
  EXPECT_EQ(m.gt_objects, 3u);
  EXPECT_EQ(m.predicted_objects, 3u);  // the wall is structure
  EXPECT_DOUBLE_EQ(m.objects_per_gt_object, 1.0);
  for (const auto& [object, pieces] : m.pieces_per_gt_object) {
    EXPECT_EQ(pieces, 1u) << object;
  }
  // Nothing predicted: every score 0.
  const SceneMetrics none = EvaluateScene(f.gt, {}, kThings, Tight());
  EXPECT_EQ(none.covered_points, 0u);
  EXPECT_DOUBLE_EQ(none.mean_iou, 0.0);
  EXPECT_DOUBLE_EQ(none.ap50, 0.0);
}

TEST(SceneMetrics, SwappedClassesLoseTheirIouAndPrecision) {
  const Fixture f;
  const std::vector<PredictedObject> predicted = {
      {10, kWall, 5, f.Points(0, kWall)},
      {11, kTable, 4, f.Points(1, kChair)},
      {12, kTable, 3, f.Points(2, kChair)},
      {13, kChair, 2, f.Points(3, kTable)}};
  const SceneMetrics m = EvaluateScene(f.gt, predicted, kThings, Tight());
  // Wall 1, chair 0 / (0 + 100 + 200), table 0: mIoU 1/3.
  EXPECT_NEAR(m.mean_iou, 1.0 / 3.0, 1e-12);
  EXPECT_DOUBLE_EQ(m.ap50, 0.0);
  EXPECT_DOUBLE_EQ(m.recall50, 0.0);
  EXPECT_DOUBLE_EQ(m.precision50, 0.0);
}

TEST(SceneMetrics, AnObjectInTwoPartsCountsAsComputedByHand) {
  const Fixture f;
  // Chair 2 in two parts of 60 and 40 points, the smaller one scored highest.
  const std::vector<PredictedObject> predicted = {
      {10, kWall, 5, f.Points(0, kWall)},
      {11, kChair, 0.9, f.Points(1, kChair)},
      {12, kChair, 0.8, f.Points(2, kChair, 0, 60)},
      {13, kChair, 0.95, f.Points(2, kChair, 60, 100)},
      {14, kTable, 0.5, f.Points(3, kTable)}};
  const SceneMetrics m = EvaluateScene(f.gt, predicted, kThings, Tight());
  EXPECT_DOUBLE_EQ(m.mean_iou, 1.0);  // classes are all right
  // IoU 0.5: chair TPs at 0.9 and 0.8, the 0.4 part a FP at 0.95: chair AP
  // 2/3 * 1/4 + 1/2 * 1/2 = 5/12 (see ScanNetAveragePrecision), table 1.
  EXPECT_NEAR(m.ap50, (5.0 / 12.0 + 1.0) / 2.0, 1e-12);
  // IoU 0.25: both parts match chair 2, the second a duplicate scored below
  // both true positives: AP 1.
  EXPECT_DOUBLE_EQ(m.ap25, 1.0);
  EXPECT_DOUBLE_EQ(m.recall50, 1.0);
  EXPECT_DOUBLE_EQ(m.precision50, 3.0 / 4.0);
  EXPECT_DOUBLE_EQ(m.objects_per_gt_object, 4.0 / 3.0);
  EXPECT_EQ(m.pieces_per_gt_object.at(2), 2u);
  EXPECT_EQ(m.pieces_per_gt_object.at(1), 1u);
}

TEST(SceneMetrics, ReportsWhereEachGroundTruthObjectWent) {
  const Fixture f;
  // Chair 1: 70 points in a chair, 20 in the table object, 10 uncovered.
  // Chair 2 and the table: whole, in one object each.
  std::vector<Eigen::Vector3f> table = f.Points(3, kTable);
  const auto stray = f.Points(1, kChair, 70, 90);
  table.insert(table.end(), stray.begin(), stray.end());
  const std::vector<PredictedObject> predicted = {
      {11, kChair, 0.9, f.Points(1, kChair, 0, 70)},
      {12, kChair, 0.8, f.Points(2, kChair)},
      {14, kTable, 0.5, table}};
  const SceneMetrics m = EvaluateScene(f.gt, predicted, kThings, Tight());
  ASSERT_EQ(m.objects.size(), 3u);
  const GtObjectReport& c1 = m.objects[0];
  EXPECT_EQ(c1.id, 1);
  EXPECT_EQ(c1.class_id, kChair);
  EXPECT_EQ(c1.points, 100u);
  EXPECT_DOUBLE_EQ(c1.best_iou, 0.7);  // 70 / (100 + 70 - 70)
  ASSERT_EQ(c1.shares.size(), 2u);
  EXPECT_EQ(c1.shares[0].predicted_id, 11u);
  EXPECT_DOUBLE_EQ(c1.shares[0].share, 0.7);
  EXPECT_EQ(c1.shares[1].predicted_id, 14u);
  EXPECT_EQ(c1.shares[1].class_id, kTable);
  EXPECT_DOUBLE_EQ(c1.shares[1].share, 0.2);
  EXPECT_NEAR(c1.uncovered, 0.1, 1e-12);
  EXPECT_DOUBLE_EQ(m.objects[1].best_iou, 1.0);
  // The table object holds 120 points, 100 of them the table's.
  EXPECT_NEAR(m.objects[2].best_iou, 100.0 / 120.0, 1e-12);
  EXPECT_DOUBLE_EQ(m.objects[2].uncovered, 0.0);
  EXPECT_EQ(c1.views, 0) << "not known without per-point views";
  // Per-point views (ObservedViews): an object reports its most-seen point.
  SceneGroundTruth gt = f.gt;
  gt.views.assign(gt.points.size(), 1);
  for (size_t i = 0; i < gt.points.size(); ++i) {
    if (gt.instance[i] == 2 && i % 7 == 0) gt.views[i] = 3;
  }
  const SceneMetrics with_views =
      EvaluateScene(gt, predicted, kThings, Tight());
  ASSERT_EQ(with_views.objects.size(), 3u);
  EXPECT_EQ(with_views.objects[0].views, 1);
  EXPECT_EQ(with_views.objects[1].views, 3);
  EXPECT_EQ(with_views.objects[2].views, 1);
}

TEST(SceneMetrics, MergedNeighboursMatchNeitherAtHalf) {
  const Fixture f;
  std::vector<Eigen::Vector3f> both = f.Points(1, kChair);
  const auto second = f.Points(2, kChair);
  both.insert(both.end(), second.begin(), second.end());
  const std::vector<PredictedObject> predicted = {
      {11, kChair, 0.9, both}, {14, kTable, 0.5, f.Points(3, kTable)}};
  const SceneMetrics m = EvaluateScene(f.gt, predicted, kThings, Tight());
  // IoU with each chair exactly 0.5, not above: chair AP50 0, table 1.
  EXPECT_DOUBLE_EQ(m.ap50, 0.5);
  // At 0.25 the merged object finds one chair (recall 1/2): AP 1/2.
  EXPECT_DOUBLE_EQ(m.ap25, (0.5 + 1.0) / 2.0);
  EXPECT_DOUBLE_EQ(m.recall50, 1.0 / 3.0);
}

TEST(SceneMetrics, GroundTruthFilesNeedClassesAndInstances) {
  semrec::testing::TempDir dir;
  io::PlyData ply;
  ply.points = {{0, 0, 0}, {1, 0, 0}};
  ply.int_properties = {{"semantic", {1, 2}}, {"instance", {0, 5}}};
  io::WritePly(dir / "gt.ply", ply);
  const SceneGroundTruth gt = ReadSceneGroundTruth(dir / "gt.ply");
  EXPECT_EQ(gt.instance, (std::vector<int32_t>{0, 5}));
  ply.int_properties.pop_back();
  io::WritePly(dir / "no_instance.ply", ply);
  try {
    ReadSceneGroundTruth(dir / "no_instance.ply");
    ADD_FAILURE() << "accepted";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("no_instance.ply"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("'instance'"), std::string::npos);
  }
}

}  // namespace
}  // namespace semrec::eval
