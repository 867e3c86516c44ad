#include "semrec/eval/mot.h"

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/testing/test_util.h"

namespace semrec::eval {
namespace {

// Reference values from three independent evaluators (py-motmetrics, TrackEval,
// mmtracking) for a published tracker's output on MOT15 TUD-Campus
// (../shared/data/README.md).
TEST(MotMetrics, ReproducesReferenceEvaluatorsOnTudCampus) {
  SEMREC_REQUIRE_SAMPLE_DATA(dir, "mot15_tud_campus");
  const auto gt = io::ReadMotFile(dir / "gt/gt.txt");
  const auto result = io::ReadMotFile(dir / "reference_tracker_output.txt");
  const MotMetrics m = EvaluateMot(gt, result);
  EXPECT_NEAR(m.mota, 0.526462, 5e-7);
  EXPECT_NEAR(m.idf1, 0.557659, 5e-7);
  EXPECT_NEAR(m.idp, 0.729730, 5e-7);
  EXPECT_NEAR(m.idr, 0.451253, 5e-7);
  EXPECT_NEAR(m.recall, 0.582173, 5e-7);
  EXPECT_NEAR(m.precision, 0.941441, 5e-7);
  EXPECT_EQ(m.false_positives, 13u);
  EXPECT_EQ(m.false_negatives, 150u);
  EXPECT_EQ(m.id_switches, 7u);
  EXPECT_EQ(m.fragmentations, 7u);
  EXPECT_NEAR(m.motp, 0.277201, 5e-7);
  EXPECT_NEAR(m.hota, 0.3914, 5e-5);
  EXPECT_NEAR(m.deta, 0.4180, 5e-5);
  EXPECT_NEAR(m.assa, 0.3691, 5e-5);
}

TEST(MotMetrics, PerfectAndEmptyResults) {
  std::vector<io::MotBox> gt;
  for (int f = 1; f <= 5; ++f) {
    gt.push_back({f, 1, 10.0 * f, 0, 20, 40});
    gt.push_back({f, 2, 200, 10.0 * f, 30, 60});
  }
  const MotMetrics perfect = EvaluateMot(gt, gt);
  EXPECT_DOUBLE_EQ(perfect.mota, 1.0);
  EXPECT_DOUBLE_EQ(perfect.idf1, 1.0);
  EXPECT_NEAR(perfect.hota, 1.0, 1e-12);
  EXPECT_EQ(perfect.mostly_tracked, 2u);
  const MotMetrics empty = EvaluateMot(gt, {});
  EXPECT_DOUBLE_EQ(empty.mota, 0.0);
  EXPECT_EQ(empty.false_negatives, 10u);
  EXPECT_EQ(empty.mostly_lost, 2u);
  // Swapping the two ids half-way is one switch per track.
  std::vector<io::MotBox> swapped = gt;
  for (auto& b : swapped) {
    if (b.frame >= 4) b.id = 3 - b.id;
  }
  const MotMetrics s = EvaluateMot(gt, swapped);
  EXPECT_EQ(s.id_switches, 2u);
  EXPECT_DOUBLE_EQ(s.mota, 1.0 - 2.0 / 10.0);
  EXPECT_DOUBLE_EQ(s.idf1, 0.6);  // 6 of 10 boxes keep their identity
}

TEST(MotIo, MalformedLinesNameTheLine) {
  semrec::testing::TempDir dir;
  semrec::testing::WriteText(dir / "a.txt", "1,1,0,0,10,10,1\n2,1,0,0,10\n");
  EXPECT_THROW(io::ReadMotFile(dir / "a.txt"), FormatError);
  semrec::testing::WriteText(dir / "b.txt", "1,1,0,0,10,10\n2,1,x,0,10,10\n");
  try {
    io::ReadMotFile(dir / "b.txt");
    FAIL();
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("line 2: 'x' is not a number"),
              std::string::npos);
  }
  semrec::testing::WriteText(dir / "c.txt", "1,1,0,0,-10,10\n");
  EXPECT_THROW(io::ReadMotFile(dir / "c.txt"), FormatError);
  semrec::testing::WriteText(dir / "d.txt", "3,1,0,0,10,10\n\n1,2,0,0,5,5\n");
  const auto boxes = io::ReadMotFile(dir / "d.txt");  // out of order: sorted
  ASSERT_EQ(boxes.size(), 2u);
  EXPECT_EQ(boxes[0].frame, 1);
  semrec::testing::WriteText(dir / "e.txt", "");
  EXPECT_TRUE(io::ReadMotFile(dir / "e.txt").empty());
  io::WriteMotFile(dir / "f.txt", boxes);
  EXPECT_EQ(io::ReadMotFile(dir / "f.txt").size(), 2u);
}

}  // namespace
}  // namespace semrec::eval
