#include "semrec/segment/vote.h"

#include <map>
#include <set>

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/core/random.h"
#include "semrec/testing/masks.h"

namespace semrec::segment {
namespace {

using testing::RectMask;

TEST(Vote, MajorityClassTakesTheWholeMask) {
  // 10 x 4: left 6 columns class 3, right 4 columns class 5. One mask over
  // columns 2..8 (7 columns: 4 of class 3, 3 of class 5) -> class 3.
  LabelMap semantic(10, 4);
  for (int y = 0; y < 4; ++y) {
    for (int x = 0; x < 10; ++x) semantic(x, y) = x < 6 ? 3 : 5;
  }
  const VoteResult r = Vote(semantic, {RectMask(10, 4, {2, 0, 9, 4})});
  ASSERT_EQ(r.mask_labels.size(), 1u);
  EXPECT_EQ(r.mask_labels[0], 3);
  EXPECT_FLOAT_EQ(r.mask_agreement[0], 16.0f / 28.0f);
  for (int y = 0; y < 4; ++y) {
    for (int x = 0; x < 10; ++x) {
      const bool inside = x >= 2 && x < 9;
      EXPECT_EQ(r.semantic(x, y), inside ? 3 : semantic(x, y)) << x << "," << y;
      // Outside the mask: one instance per class (3 -> 2, 5 -> 3).
      EXPECT_EQ(r.instance(x, y), inside ? 1 : (x < 2 ? 2 : 3));
    }
  }
}

TEST(Vote, LaterSmallerMasksKeepTheirClassOnOverlaps) {
  // A table (class 7) with a cup (class 9) on it; the table mask covers the
  // cup too. Large first, small last: the cup keeps class 9.
  LabelMap semantic(20, 20, 1, 0);
  for (int y = 5; y < 20; ++y) {
    for (int x = 0; x < 20; ++x) semantic(x, y) = 7;
  }
  for (int y = 8; y < 12; ++y) {
    for (int x = 8; x < 12; ++x) semantic(x, y) = 9;
  }
  const std::vector<Mask> masks = {RectMask(20, 20, {0, 5, 20, 20}),
                                   RectMask(20, 20, {8, 8, 12, 12})};
  const VoteResult r = Vote(semantic, masks);
  EXPECT_EQ(r.mask_labels, (std::vector<uint16_t>{7, 9}));
  EXPECT_EQ(r.semantic(10, 10), 9);
  EXPECT_EQ(r.instance(10, 10), 2);
  EXPECT_EQ(r.instance(2, 10), 1);
  EXPECT_EQ(r.semantic(2, 2), 0);  // in no mask: the semantic label
  EXPECT_EQ(r.instance(2, 2), 3);  // ... and the instance of class 0
  EXPECT_EQ(r.unmasked_classes, (std::vector<uint16_t>{0}));
}

TEST(Vote, TiesGoToTheSmallerClassId) {
  LabelMap semantic(4, 1);
  semantic(0, 0) = semantic(1, 0) = 8;
  semantic(2, 0) = semantic(3, 0) = 2;
  EXPECT_EQ(Vote(semantic, {RectMask(4, 1, {0, 0, 4, 1})}).mask_labels[0], 2);
}

// Straightforward implementation (per-mask full-image scans) as reference.
VoteResult NaiveVote(const LabelMap& semantic, const std::vector<Mask>& masks) {
  VoteResult r;
  r.semantic = semantic;
  r.instance = LabelMap(semantic.width(), semantic.height());
  for (size_t m = 0; m < masks.size(); ++m) {
    const Image<uint8_t> full = masks[m].ToImage();
    std::vector<int64_t> counts(65536, 0);
    for (size_t i = 0; i < full.NumPixels(); ++i) {
      if (full.values()[i]) ++counts[semantic.values()[i]];
    }
    uint16_t best = 0;
    for (int c = 1; c < 65536; ++c) {
      if (counts[c] > counts[best]) best = static_cast<uint16_t>(c);
    }
    r.mask_labels.push_back(best);
    for (size_t i = 0; i < full.NumPixels(); ++i) {
      if (full.values()[i])
        r.instance.values()[i] = static_cast<uint16_t>(m + 1);
    }
  }
  for (size_t i = 0; i < r.instance.NumPixels(); ++i) {
    if (r.instance.values()[i]) {
      r.semantic.values()[i] = r.mask_labels[r.instance.values()[i] - 1];
    }
  }
  std::set<uint16_t> classes;
  for (size_t i = 0; i < r.instance.NumPixels(); ++i) {
    if (!r.instance.values()[i]) classes.insert(r.semantic.values()[i]);
  }
  std::map<uint16_t, uint16_t> ids;
  for (uint16_t c : classes)
    ids[c] = static_cast<uint16_t>(masks.size() + 1 + ids.size());
  for (size_t i = 0; i < r.instance.NumPixels(); ++i) {
    if (!r.instance.values()[i]) {
      r.instance.values()[i] = ids.at(r.semantic.values()[i]);
    }
  }
  return r;
}

TEST(Vote, AgreesWithTheStraightforwardImplementation) {
  Rng rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const int w = 64, h = 48;
    LabelMap semantic(w, h);
    for (auto& v : semantic.values())
      v = static_cast<uint16_t>(rng.UniformInt(0, 5));
    std::vector<Mask> masks;
    for (int m = 0; m < 12; ++m) {
      Image<uint8_t> img(w, h);
      const int cx = rng.UniformInt(0, w - 1), cy = rng.UniformInt(0, h - 1);
      const int r = rng.UniformInt(2, 15);
      for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
          img(x, y) = (x - cx) * (x - cx) + (y - cy) * (y - cy) <= r * r &&
                      rng.Uniform() < 0.9;
        }
      }
      masks.push_back(MaskFromImage(img));
    }
    const VoteResult fast = Vote(semantic, masks);
    const VoteResult naive = NaiveVote(semantic, masks);
    EXPECT_EQ(fast.mask_labels, naive.mask_labels);
    EXPECT_EQ(fast.semantic, naive.semantic);
    EXPECT_EQ(fast.instance, naive.instance);
  }
}

TEST(Vote, RejectsMasksOfAnotherImage) {
  LabelMap semantic(8, 8);
  EXPECT_THROW(Vote(semantic, {RectMask(9, 8, {0, 0, 2, 2})}), InvalidArgument);
  EXPECT_NO_THROW(Vote(semantic, {}));
}

}  // namespace
}  // namespace semrec::segment
