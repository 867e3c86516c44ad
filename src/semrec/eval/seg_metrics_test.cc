#include "semrec/eval/seg_metrics.h"

#include <cmath>
#include <map>

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/io/image_io.h"
#include "semrec/testing/test_util.h"

namespace semrec::eval {
namespace {

LabelMap FromRows(const std::vector<std::vector<uint16_t>>& rows) {
  LabelMap m(int(rows[0].size()), int(rows.size()));
  for (size_t y = 0; y < rows.size(); ++y) {
    for (size_t x = 0; x < rows[y].size(); ++x) m(int(x), int(y)) = rows[y][x];
  }
  return m;
}

const ClassSegMetrics* Find(const SegMetrics& m, uint16_t id) {
  for (const auto& c : m.classes) {
    if (c.id == id) return &c;
  }
  return nullptr;
}

TEST(SegMetrics, HandComputedIouAccuracyAndIgnoredPixels) {
  // GT 0 is unlabelled: the prediction there (class 3) counts for nothing.
  const LabelMap gt = FromRows({{1, 1, 2, 2}, {1, 1, 2, 0}});
  const LabelMap pred = FromRows({{1, 2, 2, 2}, {1, 1, 1, 3}});
  SegEvaluator e;
  e.Add(pred, gt);
  const SegMetrics m = e.Result();
  // 7 valid pixels, 5 correct.
  EXPECT_EQ(m.valid_pixels, 7);
  EXPECT_DOUBLE_EQ(m.pixel_accuracy, 5.0 / 7.0);
  ASSERT_EQ(m.classes.size(), 2u);
  // Class 1: gt 4, pred 4, both 3 -> IoU 3/5, acc 3/4.
  EXPECT_DOUBLE_EQ(Find(m, 1)->iou, 0.6);
  EXPECT_DOUBLE_EQ(Find(m, 1)->accuracy, 0.75);
  // Class 2: gt 3, pred 3, both 2 -> IoU 2/4, acc 2/3.
  EXPECT_DOUBLE_EQ(Find(m, 2)->iou, 0.5);
  EXPECT_DOUBLE_EQ(Find(m, 2)->accuracy, 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(m.mean_iou, 0.55);
  EXPECT_DOUBLE_EQ(m.mean_accuracy, (0.75 + 2.0 / 3.0) / 2);
  EXPECT_EQ(Find(m, 3), nullptr);

  // 255 is ignored as well; 0 becomes a class when ignore_zero is off.
  SegEvalOptions options;
  options.ignore_zero = false;
  SegEvaluator e2(options);
  e2.Add(FromRows({{0, 5, 255}}), FromRows({{0, 5, 255}}));
  EXPECT_EQ(e2.Result().valid_pixels, 2);
  EXPECT_DOUBLE_EQ(e2.Result().mean_iou, 1.0);
  EXPECT_THROW(e.Add(FromRows({{1, 1}}), gt), InvalidArgument);
}

// Independent band: mask pixels with a non-mask pixel (or the outside of the
// image) within Chebyshev distance d.
Image<uint8_t> NaiveBand(const Image<uint8_t>& mask, int d) {
  Image<uint8_t> band(mask.width(), mask.height());
  for (int y = 0; y < mask.height(); ++y) {
    for (int x = 0; x < mask.width(); ++x) {
      if (!mask(x, y)) continue;
      bool near = false;
      for (int v = y - d; v <= y + d && !near; ++v) {
        for (int u = x - d; u <= x + d && !near; ++u) {
          near = u < 0 || v < 0 || u >= mask.width() || v >= mask.height() ||
                 !mask(u, v);
        }
      }
      band(x, y) = near;
    }
  }
  return band;
}

TEST(SegMetrics, BoundaryIouOfShiftedSquaresMatchesAnIndependentComputation) {
  // 100 x 100: diagonal 141.4 -> d = round(0.02 * 141.4) = 3.
  const auto square = [](int x0) {
    LabelMap m(100, 100, 1, 2);
    for (int y = 20; y < 60; ++y) {
      for (int x = x0; x < x0 + 40; ++x) m(x, y) = 1;
    }
    return m;
  };
  for (int shift : {0, 2, 5, 10}) {
    SegEvaluator e;
    e.Add(square(20 + shift), square(20));
    const SegMetrics m = e.Result();
    for (uint16_t c : {1, 2}) {
      Image<uint8_t> g(100, 100), p(100, 100);
      const LabelMap gt = square(20), pred = square(20 + shift);
      for (size_t i = 0; i < g.NumPixels(); ++i) {
        g.values()[i] = gt.values()[i] == c;
        p.values()[i] = pred.values()[i] == c;
      }
      const auto gb = NaiveBand(g, 3), pb = NaiveBand(p, 3);
      int64_t inter = 0, uni = 0;
      for (size_t i = 0; i < gb.NumPixels(); ++i) {
        inter += gb.values()[i] && pb.values()[i];
        uni += gb.values()[i] || pb.values()[i];
      }
      EXPECT_DOUBLE_EQ(Find(m, c)->boundary_iou, double(inter) / uni)
          << "shift " << shift << " class " << c;
    }
    if (shift == 0) {
      EXPECT_DOUBLE_EQ(m.mean_boundary_iou, 1.0);
      EXPECT_DOUBLE_EQ(m.mean_boundary_f, 1.0);
    }
    if (shift == 2) {
      // Every contour pixel is within 2 px of the other contour.
      EXPECT_DOUBLE_EQ(Find(m, 1)->boundary_f, 1.0);
    }
    if (shift == 10) {
      EXPECT_LT(Find(m, 1)->boundary_f, 0.8);
    }
  }
}

TEST(SegMetrics, Ade20kSamplesWithPerturbedPredictions) {
  SEMREC_REQUIRE_SAMPLE_DATA(ade, "ade20k_val_3");
  std::vector<LabelMap> gts;
  for (const auto& [pred, gt] :
       MatchSegFiles(ade / "annotations", ade / "annotations")) {
    EXPECT_EQ(pred, gt);
    gts.push_back(io::ReadLabelImage(gt));
  }
  ASSERT_EQ(gts.size(), 3u);
  {
    SegEvaluator e;
    for (const auto& g : gts) e.Add(g, g);
    const SegMetrics m = e.Result();
    EXPECT_DOUBLE_EQ(m.pixel_accuracy, 1.0);
    EXPECT_DOUBLE_EQ(m.mean_iou, 1.0);
    EXPECT_DOUBLE_EQ(m.mean_boundary_iou, 1.0);
    EXPECT_GT(m.classes.size(), 10u);
  }
  // Relabel the most frequent class of all images to another present class:
  // expected numbers by plain counting.
  std::map<uint16_t, int64_t> freq;
  for (const auto& g : gts) {
    for (uint16_t v : g.values()) {
      if (v != 0) ++freq[v];
    }
  }
  uint16_t a = 0, b = 0;
  for (const auto& [c, n] : freq) {
    if (a == 0 || n > freq[a]) a = c;
  }
  for (const auto& [c, n] : freq) {
    if (c != a && (b == 0 || n > freq[b])) b = c;
  }
  SegEvaluator e;
  int64_t valid = 0;
  for (const auto& g : gts) {
    LabelMap p = g;
    for (auto& v : p.values()) {
      if (v == a) v = b;
    }
    e.Add(p, g);
    for (uint16_t v : g.values()) valid += v != 0;
  }
  const SegMetrics m = e.Result();
  EXPECT_EQ(m.valid_pixels, valid);
  EXPECT_NEAR(m.pixel_accuracy, 1.0 - double(freq[a]) / valid, 1e-12);
  EXPECT_DOUBLE_EQ(Find(m, a)->iou, 0.0);
  // Class b: intersection = its own pixels, union = own + a's.
  EXPECT_NEAR(Find(m, b)->iou, double(freq[b]) / (freq[a] + freq[b]), 1e-12);
  const double others = double(m.classes.size() - 2);
  EXPECT_NEAR(
      m.mean_iou,
      (others + double(freq[b]) / (freq[a] + freq[b])) / m.classes.size(),
      1e-12);
  // Shifting predictions degrades boundaries monotonically.
  double last_biou = 1.0, last_miou = 1.0;
  for (int k : {1, 3, 8}) {
    SegEvaluator s;
    for (const auto& g : gts) {
      LabelMap p(g.width(), g.height());
      for (int y = 0; y < g.height(); ++y) {
        for (int x = 0; x < g.width(); ++x) p(x, y) = g(std::max(0, x - k), y);
      }
      s.Add(p, g);
    }
    const SegMetrics r = s.Result();
    EXPECT_LT(r.mean_boundary_iou, last_biou) << k;
    EXPECT_LT(r.mean_iou, last_miou) << k;
    last_biou = r.mean_boundary_iou;
    last_miou = r.mean_iou;
  }
}

TEST(SegMetrics, MissingPredictionsAreNamed) {
  semrec::testing::TempDir dir;
  std::filesystem::create_directories(dir.path() / "gt");
  std::filesystem::create_directories(dir.path() / "pred");
  io::WritePng(dir.path() / "gt" / "a.png", LabelMap(4, 4));
  try {
    MatchSegFiles(dir.path() / "pred", dir.path() / "gt");
    FAIL();
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("a.png"), std::string::npos);
  }
  io::WritePng(dir.path() / "pred" / "a_semantic.png", LabelMap(4, 4));
  EXPECT_EQ(MatchSegFiles(dir.path() / "pred", dir.path() / "gt").size(), 1u);
}

}  // namespace
}  // namespace semrec::eval
