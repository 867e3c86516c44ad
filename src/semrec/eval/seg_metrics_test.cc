#include "semrec/eval/seg_metrics.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/io/image_io.h"
#include "semrec/testing/test_util.h"

namespace semrec::eval {
namespace {

LabelMap FromRows(const std::vector<std::vector<uint16_t>>& rows) {
  LabelMap m(static_cast<int>(rows[0].size()), static_cast<int>(rows.size()));
  for (size_t y = 0; y < rows.size(); ++y) {
    for (size_t x = 0; x < rows[y].size(); ++x)
      m(static_cast<int>(x), static_cast<int>(y)) = rows[y][x];
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
  // Class 1: gt 4, pred 4, both 3 -> union 5, IoU 3/5, acc 3/4.
  EXPECT_EQ(Find(m, 1)->union_pixels, 5);
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
  EXPECT_EQ(e2.Result().classes.size(), 2u);
  EXPECT_DOUBLE_EQ(e2.Result().mean_iou, 1.0);
  EXPECT_THROW(e.Add(FromRows({{1, 1}}), gt), InvalidArgument);
}

TEST(SegMetrics, PredictedZeroOrIgnoreLabelIsWrongButNotAClass) {
  // As ADE20K's script: a prediction of 0 (or 255) on a labelled pixel is a
  // miss for the GT class and no class of its own.
  SegEvaluator e;
  e.Add(FromRows({{0, 1}, {255, 2}}), FromRows({{1, 1}, {2, 2}}));
  const SegMetrics m = e.Result();
  ASSERT_EQ(m.classes.size(), 2u);
  EXPECT_DOUBLE_EQ(m.pixel_accuracy, 0.5);
  // Each class: gt 2, pred 1, both 1 -> IoU 1/2, acc 1/2.
  EXPECT_DOUBLE_EQ(Find(m, 1)->iou, 0.5);
  EXPECT_DOUBLE_EQ(Find(m, 2)->accuracy, 0.5);
  EXPECT_DOUBLE_EQ(m.mean_iou, 0.5);
  EXPECT_DOUBLE_EQ(m.mean_accuracy, 0.5);
}

TEST(SegMetrics, OptionsAreChecked) {
  SegEvalOptions o;
  EXPECT_NO_THROW(o.Check());
  o.boundary_dilation_ratio = 0;
  EXPECT_THROW(SegEvaluator{o}, InvalidArgument);
  o = {};
  o.boundary_tolerance_px = -1;
  EXPECT_THROW(o.Check(), InvalidArgument);
  o = {};
  o.ignore_label = 70000;
  EXPECT_THROW(o.Check(), InvalidArgument);
  EXPECT_EQ(BoundaryBandWidth(0.02, 100, 100), 3);   // 0.02 * 141.4 = 2.83
  EXPECT_EQ(BoundaryBandWidth(0.02, 683, 512), 17);  // 0.02 * 853.6 = 17.07
  EXPECT_EQ(BoundaryBandWidth(0.02, 4, 4), 1);       // at least 1
}

// A 100 x 100 map: class 1 in x0..x0+39 x 20..59, class 2 elsewhere.
LabelMap Square(int x0) {
  LabelMap m(100, 100, 1, 2);
  for (int y = 20; y < 60; ++y) {
    for (int x = x0; x < x0 + 40; ++x) m(x, y) = 1;
  }
  return m;
}

TEST(SegMetrics, BoundaryOfOffsetSquaresByHand) {
  // GT square at x 20..59, prediction shifted by 10 to x 30..69; d = 3.
  SegEvaluator e;
  e.Add(Square(30), Square(20));
  const SegMetrics m = e.Result();
  // Class 1: each band is a 3-px frame, 40^2 - 34^2 = 444 pixels. They share
  // the top and bottom 3 rows over x 30..59: 6 * 30 = 180. Union 888 - 180.
  EXPECT_EQ(Find(m, 1)->boundary_intersection, 180);
  EXPECT_EQ(Find(m, 1)->boundary_union, 708);
  EXPECT_DOUBLE_EQ(Find(m, 1)->boundary_iou, 180.0 / 708.0);
  // Class 2: the image border counts as contour (3-px ring, 100^2 - 94^2 =
  // 1164, shared) plus a ring outside the square (46^2 - 40^2 = 516) that
  // the two maps share in rows 17..19 and 60..62 over x 27..62: 6 * 36.
  // Intersection 1164 + 216 = 1380, union 2 * 1680 - 1380 = 1980.
  EXPECT_EQ(Find(m, 2)->boundary_intersection, 1380);
  EXPECT_EQ(Find(m, 2)->boundary_union, 1980);
  EXPECT_DOUBLE_EQ(m.mean_boundary_iou, (180.0 / 708 + 1380.0 / 1980) / 2);
  // Boundary F of class 1 at 2 px: both contours have 4 * 39 = 156 pixels.
  // Predicted contour near the GT one: top and bottom rows x 30..61 (2 * 32)
  // and the left column's two pixels next to each corner row (4): 68. By
  // symmetry recall is 68 / 156 too, so F = 68 / 156.
  EXPECT_DOUBLE_EQ(Find(m, 1)->boundary_precision, 68.0 / 156.0);
  EXPECT_DOUBLE_EQ(Find(m, 1)->boundary_recall, 68.0 / 156.0);
  EXPECT_DOUBLE_EQ(Find(m, 1)->boundary_f, 68.0 / 156.0);
  // Region metrics: intersection 40 * 30, union 2 * 1600 - 1200.
  EXPECT_DOUBLE_EQ(Find(m, 1)->iou, 1200.0 / 2000.0);
}

// Independent band: mask pixels with a non-mask pixel (or the outside of the
// image) within Chebyshev distance d, by brute force.
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

TEST(SegMetrics, BoundaryIouOfShiftedSquaresMatchesBruteForce) {
  for (int shift : {0, 2, 5, 10, 45}) {
    SegEvaluator e;
    e.Add(Square(20 + shift), Square(20));
    const SegMetrics m = e.Result();
    for (uint16_t c : {1, 2}) {
      Image<uint8_t> g(100, 100), p(100, 100);
      const LabelMap gt = Square(20), pred = Square(20 + shift);
      for (size_t i = 0; i < g.NumPixels(); ++i) {
        g.values()[i] = gt.values()[i] == c;
        p.values()[i] = pred.values()[i] == c;
      }
      const auto gb = NaiveBand(g, 3), pb = NaiveBand(p, 3);
      EXPECT_EQ(BoundaryBand(g, 3), gb);
      int64_t inter = 0, uni = 0;
      for (size_t i = 0; i < gb.NumPixels(); ++i) {
        inter += gb.values()[i] && pb.values()[i];
        uni += gb.values()[i] || pb.values()[i];
      }
      EXPECT_DOUBLE_EQ(Find(m, c)->boundary_iou,
                       static_cast<double>(inter) / uni)
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
  }
}

// A separate, straightforward evaluation for the real-data tests: per image
// and class, full-image masks, plain counting, bands from a two-pass
// chessboard distance transform, contour matches by searching a window.
struct RefCounts {
  int64_t inter = 0, gt = 0, pred = 0;
  int64_t b_inter = 0, b_union = 0;
  int64_t p_c = 0, p_matched = 0, g_c = 0, g_matched = 0;
};

// Chessboard distance of each mask pixel to the nearest non-mask pixel, the
// outside of the image counting as non-mask; 0 off the mask.
std::vector<int> ChessDistance(const std::vector<uint8_t>& mask, int w, int h) {
  std::vector<int> dist(mask.size());
  const auto at = [&](int x, int y) {
    return x < 0 || y < 0 || x >= w || y >= h
               ? 0
               : dist[static_cast<size_t>(y) * w + x];
  };
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      int& v = dist[static_cast<size_t>(y) * w + x];
      v = mask[static_cast<size_t>(y) * w + x]
              ? 1 + std::min({at(x - 1, y), at(x - 1, y - 1), at(x, y - 1),
                              at(x + 1, y - 1)})
              : 0;
    }
  }
  for (int y = h - 1; y >= 0; --y) {
    for (int x = w - 1; x >= 0; --x) {
      int& v = dist[static_cast<size_t>(y) * w + x];
      if (v) {
        v = std::min(v, 1 + std::min({at(x + 1, y), at(x + 1, y + 1),
                                      at(x, y + 1), at(x - 1, y + 1)}));
      }
    }
  }
  return dist;
}

int64_t CountMatched(const std::vector<int>& contour_dist,
                     const std::vector<int>& other_dist, int w, int h, int t) {
  int64_t matched = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (contour_dist[static_cast<size_t>(y) * w + x] != 1) continue;
      bool found = false;
      for (int v = std::max(0, y - t); v <= std::min(h - 1, y + t); ++v) {
        for (int u = std::max(0, x - t); u <= std::min(w - 1, x + t); ++u) {
          found |= other_dist[static_cast<size_t>(v) * w + u] == 1 &&
                   (u - x) * (u - x) + (v - y) * (v - y) <= t * t;
        }
      }
      matched += found;
    }
  }
  return matched;
}

std::map<int, RefCounts> ReferenceCounts(
    const std::vector<std::pair<LabelMap, LabelMap>>& pairs) {
  std::map<int, RefCounts> out;
  for (const auto& [pred, gt] : pairs) {
    const int w = gt.width(), h = gt.height();
    const int d = static_cast<int>(
        std::lround(0.02 * std::sqrt(static_cast<double>(w * w + h * h))));
    std::set<int> classes;
    for (size_t i = 0; i < gt.NumPixels(); ++i) {
      const int g = gt.values()[i], p = pred.values()[i];
      if (g == 0 || g == 255) continue;
      classes.insert(g);
      if (p != 0 && p != 255) classes.insert(p);
    }
    for (int c : classes) {
      std::vector<uint8_t> gm(gt.NumPixels()), pm(gt.NumPixels());
      RefCounts& r = out[c];
      for (size_t i = 0; i < gt.NumPixels(); ++i) {
        const int g = gt.values()[i], p = pred.values()[i];
        const bool valid = g != 0 && g != 255;
        gm[i] = valid && g == c;
        pm[i] = valid && p == c;
        r.gt += gm[i];
        r.pred += pm[i];
        r.inter += gm[i] && pm[i];
      }
      const auto gd = ChessDistance(gm, w, h), pd = ChessDistance(pm, w, h);
      for (size_t i = 0; i < gd.size(); ++i) {
        const bool gb = gd[i] >= 1 && gd[i] <= d, pb = pd[i] >= 1 && pd[i] <= d;
        r.b_inter += gb && pb;
        r.b_union += gb || pb;
        r.g_c += gd[i] == 1;
        r.p_c += pd[i] == 1;
      }
      r.p_matched += CountMatched(pd, gd, w, h, 2);
      r.g_matched += CountMatched(gd, pd, w, h, 2);
    }
  }
  return out;
}

void ExpectMatchesReference(
    const std::vector<std::pair<LabelMap, LabelMap>>& pairs,
    const std::string& what) {
  SCOPED_TRACE(what);
  SegEvaluator e;
  for (const auto& [pred, gt] : pairs) e.Add(pred, gt);
  const SegMetrics m = e.Result();
  const std::map<int, RefCounts> ref = ReferenceCounts(pairs);
  ASSERT_EQ(m.classes.size(), ref.size());
  double miou = 0, biou = 0, bf = 0, macc = 0;
  int n_acc = 0;
  for (const auto& [c, r] : ref) {
    const ClassSegMetrics* k = Find(m, static_cast<uint16_t>(c));
    ASSERT_NE(k, nullptr) << c;
    EXPECT_EQ(k->intersection, r.inter) << c;
    EXPECT_EQ(k->gt_pixels, r.gt) << c;
    EXPECT_EQ(k->pred_pixels, r.pred) << c;
    EXPECT_EQ(k->boundary_intersection, r.b_inter) << c;
    EXPECT_EQ(k->boundary_union, r.b_union) << c;
    miou += static_cast<double>(r.inter) /
            static_cast<double>(r.gt + r.pred - r.inter);
    if (r.gt) {
      macc += static_cast<double>(r.inter) / static_cast<double>(r.gt);
      ++n_acc;
    }
    biou += static_cast<double>(r.b_inter) / static_cast<double>(r.b_union);
    const double p = r.p_c ? static_cast<double>(r.p_matched) / r.p_c : 0.0;
    const double rc = r.g_c ? static_cast<double>(r.g_matched) / r.g_c : 0.0;
    EXPECT_NEAR(k->boundary_precision, p, 1e-12) << c;
    EXPECT_NEAR(k->boundary_recall, rc, 1e-12) << c;
    bf += p + rc > 0 ? 2 * p * rc / (p + rc) : 0.0;
  }
  EXPECT_NEAR(m.mean_iou, miou / ref.size(), 1e-12);
  EXPECT_NEAR(m.mean_accuracy, macc / n_acc, 1e-12);
  EXPECT_NEAR(m.mean_boundary_iou, biou / ref.size(), 1e-12);
  EXPECT_NEAR(m.mean_boundary_f, bf / ref.size(), 1e-12);
}

std::vector<LabelMap> ReadAdeAnnotations(const std::filesystem::path& ade) {
  std::vector<LabelMap> gts;
  for (const auto& [pred, gt] :
       MatchSegFiles(ade / "annotations", ade / "annotations")) {
    EXPECT_EQ(pred, gt);
    gts.push_back(io::ReadLabelImage(gt));
  }
  return gts;
}

LabelMap Shifted(const LabelMap& g, int k) {
  LabelMap p(g.width(), g.height());
  for (int y = 0; y < g.height(); ++y) {
    for (int x = 0; x < g.width(); ++x) p(x, y) = g(std::max(0, x - k), y);
  }
  return p;
}

TEST(SegMetrics, Ade20kGroundTruthAgainstItselfIsPerfect) {
  SEMREC_REQUIRE_SAMPLE_DATA(ade, "ade20k_val_3");
  const std::vector<LabelMap> gts = ReadAdeAnnotations(ade);
  ASSERT_EQ(gts.size(), 3u);
  SegEvaluator e;
  for (const auto& g : gts) e.Add(g, g);
  const SegMetrics m = e.Result();
  EXPECT_DOUBLE_EQ(m.pixel_accuracy, 1.0);
  EXPECT_DOUBLE_EQ(m.mean_iou, 1.0);
  EXPECT_DOUBLE_EQ(m.mean_accuracy, 1.0);
  EXPECT_DOUBLE_EQ(m.mean_boundary_iou, 1.0);
  EXPECT_DOUBLE_EQ(m.mean_boundary_f, 1.0);
  EXPECT_GT(m.classes.size(), 10u);
}

TEST(SegMetrics, Ade20kPerturbedPredictionsMatchAnIndependentComputation) {
  SEMREC_REQUIRE_SAMPLE_DATA(ade, "ade20k_val_3");
  const std::vector<LabelMap> gts = ReadAdeAnnotations(ade);
  ASSERT_EQ(gts.size(), 3u);
  // The two most frequent labelled classes over the three images.
  std::map<uint16_t, int64_t> freq;
  int64_t labelled = 0;
  for (const auto& g : gts) {
    for (uint16_t v : g.values()) {
      if (v == 0) continue;
      ++freq[v];
      ++labelled;
    }
  }
  std::vector<std::pair<int64_t, uint16_t>> by_count;
  for (const auto& [c, n] : freq) by_count.emplace_back(n, c);
  std::sort(by_count.rbegin(), by_count.rend());
  const uint16_t a = by_count[0].second, b = by_count[1].second;

  // Relabel class a as b: a's IoU is 0, b's is |b| / (|a| + |b|), every other
  // class stays perfect.
  std::vector<std::pair<LabelMap, LabelMap>> relabelled;
  for (const auto& g : gts) {
    LabelMap p = g;
    for (auto& v : p.values()) v = v == a ? b : v;
    relabelled.emplace_back(p, g);
  }
  {
    SegEvaluator e;
    for (const auto& [p, g] : relabelled) e.Add(p, g);
    const SegMetrics m = e.Result();
    EXPECT_EQ(m.valid_pixels, labelled);
    EXPECT_NEAR(m.pixel_accuracy, 1.0 - static_cast<double>(freq[a]) / labelled,
                1e-12);
    EXPECT_DOUBLE_EQ(Find(m, a)->iou, 0.0);
    const double iou_b =
        static_cast<double>(freq[b]) / static_cast<double>(freq[a] + freq[b]);
    EXPECT_NEAR(Find(m, b)->iou, iou_b, 1e-12);
    const double n = static_cast<double>(m.classes.size());
    EXPECT_NEAR(m.mean_iou, (n - 2 + iou_b) / n, 1e-12);
  }
  ExpectMatchesReference(relabelled, "relabel");

  // Unlabel (0) the left third of every prediction: those pixels are wrong
  // and 0 is no class.
  std::vector<std::pair<LabelMap, LabelMap>> blanked;
  int64_t lost = 0;
  for (const auto& g : gts) {
    LabelMap p = g;
    for (int y = 0; y < g.height(); ++y) {
      for (int x = 0; x < g.width() / 3; ++x) {
        lost += g(x, y) != 0;
        p(x, y) = 0;
      }
    }
    blanked.emplace_back(p, g);
  }
  {
    SegEvaluator e;
    for (const auto& [p, g] : blanked) e.Add(p, g);
    const SegMetrics m = e.Result();
    EXPECT_NEAR(m.pixel_accuracy, 1.0 - static_cast<double>(lost) / labelled,
                1e-12);
    EXPECT_EQ(Find(m, 0), nullptr);
  }
  ExpectMatchesReference(blanked, "blank");

  std::vector<std::pair<LabelMap, LabelMap>> shifted;
  for (const auto& g : gts) shifted.emplace_back(Shifted(g, 5), g);
  ExpectMatchesReference(shifted, "shift");
}

TEST(SegMetrics, Ade20kBoundaryMetricsDecreaseWithTheShift) {
  SEMREC_REQUIRE_SAMPLE_DATA(ade, "ade20k_val_3");
  const std::vector<LabelMap> gts = ReadAdeAnnotations(ade);
  double last_biou = 1.0, last_bf = 1.0, last_miou = 1.0;
  for (int k : {1, 2, 4, 8, 16}) {
    SegEvaluator s;
    for (const auto& g : gts) s.Add(Shifted(g, k), g);
    const SegMetrics r = s.Result();
    EXPECT_LT(r.mean_boundary_iou, last_biou) << k;
    EXPECT_LT(r.mean_boundary_f, last_bf) << k;
    EXPECT_LT(r.mean_iou, last_miou) << k;
    // Boundaries suffer more than regions.
    EXPECT_LT(r.mean_boundary_iou, r.mean_iou) << k;
    last_biou = r.mean_boundary_iou;
    last_bf = r.mean_boundary_f;
    last_miou = r.mean_iou;
  }
}

TEST(SegMetrics, MatchesFilesByStem) {
  semrec::testing::TempDir dir;
  std::filesystem::create_directories(dir.path() / "gt");
  std::filesystem::create_directories(dir.path() / "pred");
  io::WritePng(dir.path() / "gt" / "a.png", LabelMap(4, 4));
  io::WritePng(dir.path() / "gt" / "b.png", LabelMap(4, 4));
  try {
    MatchSegFiles(dir.path() / "pred", dir.path() / "gt");
    FAIL();
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("a.png"), std::string::npos);
  }
  io::WritePng(dir.path() / "pred" / "a_semantic.png", LabelMap(4, 4));
  EXPECT_THROW(MatchSegFiles(dir.path() / "pred", dir.path() / "gt"), IoError);
  const auto pairs =
      MatchSegFiles(dir.path() / "pred", dir.path() / "gt", true);
  ASSERT_EQ(pairs.size(), 1u);
  EXPECT_EQ(pairs[0].first.filename(), "a_semantic.png");
  EXPECT_THROW(MatchSegFiles(dir.path() / "nope", dir.path() / "gt"), IoError);
}

}  // namespace
}  // namespace semrec::eval

namespace semrec::eval {
namespace {

TEST(SegMetrics, UnnamedGroundTruthClassesFoldIntoTheCatchAll) {
  LabelSet top("top");
  top.Add({0, "other", {0, 0, 0}, ClassKind::kOther});
  top.Add({1, "wall", {1, 1, 1}, ClassKind::kStuff});
  top.Add({20, "chair", {2, 2, 2}, ClassKind::kThing});
  LabelMap gt(4, 1);
  gt.values() = {1, 20, 37, 0};  // wall, chair, lamp (not in the set), none
  EXPECT_EQ(FoldUnnamedIntoCatchAll(top, &gt), 1u);
  EXPECT_EQ(gt.values(), (std::vector<uint16_t>{1, 20, 0, 0}));
  // Scored with 0 ignored: predicting "wall" on the lamp costs nothing, the
  // chair called "other" does.
  LabelMap pred(4, 1);
  pred.values() = {1, 0, 1, 1};
  SegEvaluator evaluator{SegEvalOptions{}};
  evaluator.Add(pred, gt);
  const SegMetrics m = evaluator.Result();
  EXPECT_EQ(m.valid_pixels, 2);
  EXPECT_DOUBLE_EQ(m.pixel_accuracy, 0.5);
  // A set without a catch-all leaves unknown ids alone.
  LabelSet plain("plain");
  plain.Add({1, "wall", {1, 1, 1}, ClassKind::kStuff});
  LabelMap gt2(1, 1, 1, 37);
  EXPECT_EQ(FoldUnnamedIntoCatchAll(plain, &gt2), 0u);
  EXPECT_EQ(gt2(0, 0), 37);
}

}  // namespace
}  // namespace semrec::eval
