#include "semrec/fuse/mask_coverage.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/fuse/fusion.h"

namespace semrec::fuse {
namespace {

TEST(EvidenceGraph, CountsViewsOnceAndJoinsPairsOnMerge) {
  EvidenceGraph g;
  g.Record(1, 2, 10, true);
  g.Record(2, 1, 10, true);  // same view, either order: counted once
  g.Record(1, 2, 11, false);
  g.Record(1, 2, 12, false);
  g.Record(1, 2, 12, true);  // one mask in a view beats two
  const PairEvidence* e = g.Find(2, 1);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->one(), 2u);  // views 10, 12
  EXPECT_EQ(e->two(), 1u);  // view 11
  // 3 merges into 1: (3, 2) joins (1, 2), (1, 3) disappears.
  g.Record(3, 2, 11, true);
  g.Record(3, 2, 13, false);
  g.Record(1, 3, 14, true);
  g.Absorb(1, 3);
  EXPECT_EQ(g.Find(1, 3), nullptr);
  e = g.Find(1, 2);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->one_frames, (std::vector<uint32_t>{10, 11, 12}));
  EXPECT_EQ(e->two_frames, (std::vector<uint32_t>{13}));
  g.Erase(2);
  EXPECT_TRUE(g.pairs().empty());
}

TEST(EvidenceGraph, SaysOneWhenOneOutweighsTwo) {
  EvidenceOptions o;  // min_one_views 2, min_views 3, two_weight 0.5
  PairEvidence e;
  e.one_frames = {1, 2};
  e.two_frames = {3, 4};
  EXPECT_TRUE(EvidenceGraph::SaysOne(e, o));  // 2 > 0.5 * 2
  e.two_frames = {3, 4, 5, 6};
  EXPECT_FALSE(EvidenceGraph::SaysOne(e, o));  // 2 > 0.5 * 4 fails
  e.one_frames = {1, 2, 7};
  EXPECT_TRUE(EvidenceGraph::SaysOne(e, o));  // 3 > 2
  e.one_frames = {1, 2};
  e.two_frames = {};
  EXPECT_FALSE(EvidenceGraph::SaysOne(e, o));  // two views only: too early
  e.one_frames = {1};
  e.two_frames = {3, 4};
  EXPECT_FALSE(EvidenceGraph::SaysOne(e, o));  // a single view of one mask
  o.two_weight = 0.0;
  o.min_views = 1;
  EXPECT_FALSE(EvidenceGraph::SaysOne(e, o));  // still below min_one_views
}

TEST(EvidenceGraph, ViewsGiveOneForASharedHolderAndTwoForNeighbours) {
  // Segments (rows) x objects (columns): points of the segment on the object.
  const std::vector<std::vector<uint32_t>> near = {
      {10, 8, 0, 0},  // segment 0 holds objects 0 and 1
      {1, 0, 9, 0},   // segment 1 holds object 2
      {0, 0, 0, 3},   // object 3: too few points to count as seen
  };
  EvidenceOptions o;
  o.min_seen_points = 4;
  const std::vector<size_t> sizes = {20, 20, 20, 20};
  const ViewEvidence view =
      EvaluateView(near, sizes, o, [](size_t, size_t) { return true; });
  EXPECT_EQ(view.holder, (std::vector<int64_t>{0, 0, 1, -1}));
  using P = std::tuple<size_t, size_t, bool>;
  EXPECT_EQ(view.pairs,
            (std::vector<P>{{0, 1, true}, {0, 2, false}, {1, 2, false}}));
  // Far apart objects give no views either way.
  const ViewEvidence apart =
      EvaluateView(near, sizes, o, [](size_t, size_t) { return false; });
  EXPECT_TRUE(apart.pairs.empty());
  // An object split evenly between two segments has no holder.
  const ViewEvidence split = EvaluateView({{5, 0}, {5, 0}}, {20, 20}, o,
                                          [](size_t, size_t) { return true; });
  EXPECT_EQ(split.holder[0], 0);  // 5 >= 0.5 * 10: the first one
  o.min_hold_share = 0.6;
  const ViewEvidence strict = EvaluateView({{5, 0}, {5, 0}}, {20, 20}, o,
                                           [](size_t, size_t) { return true; });
  EXPECT_EQ(strict.holder[0], -1);
  // A large object grazed by a few points is not seen (10 < 0.2 x 60).
  o = {};
  const ViewEvidence grazed =
      EvaluateView({{10, 9}}, {60, 20}, o, [](size_t, size_t) { return true; });
  EXPECT_EQ(grazed.holder, (std::vector<int64_t>{-1, 0}));
  EXPECT_TRUE(grazed.pairs.empty());
}

TEST(EvidenceOptions, AreChecked) {
  EvidenceOptions o;
  o.min_hold_share = 0;
  EXPECT_THROW(o.Check(), InvalidArgument);
  o = {};
  o.cross_class_alpha = 1.5;
  EXPECT_THROW(o.Check(), InvalidArgument);
  FusionOptions f;
  f.evidence.two_weight = -1;
  EXPECT_THROW(SceneFusion{f}, InvalidArgument);
  EXPECT_EQ(ParseMerge("paper"), FusionOptions::Merge::kPaper);
  EXPECT_THROW(ParseMerge("magic"), InvalidArgument);
}

// A surface patch: the plane z = 0.05 over [x0, x1] x [0, 0.5], sampled at 1 cm
// with noise, as one view would see it (off the voxel boundaries, as real
// surfaces are).
Cloud Patch(float x0, float x1, std::mt19937& rng, float y1 = 0.5f) {
  std::normal_distribution<float> g(0, 0.003f);
  Cloud c;
  const int nx = static_cast<int>(std::lround((x1 - x0) / 0.01f));
  const int ny = static_cast<int>(std::lround(y1 / 0.01f));
  for (int i = 0; i < nx; ++i) {
    for (int j = 0; j < ny; ++j) {
      c.emplace_back(x0 + 0.01f * static_cast<float>(i) + g(rng),
                     0.01f * static_cast<float>(j) + g(rng), 0.05f + g(rng));
    }
  }
  return c;
}

FrameSegment SegmentOf(uint16_t cls, uint16_t label, Cloud points) {
  FrameSegment s;
  s.class_id = cls;
  s.source_label = label;
  s.points_world = std::move(points);
  return s;
}

// The two halves of one object, first seen as two masks; later views each see
// a strip across the seam (and beyond the halves) inside one mask. The strips
// overlap neither half enough for sigma > alpha, so the paper's rule keeps the
// halves and makes the strip a third object; the views say one.
TEST(FusionEvidence, PartsThatViewsShowInOneMaskBecomeOneObject) {
  for (const auto merge :
       {FusionOptions::Merge::kPaper, FusionOptions::Merge::kEvidence}) {
    std::mt19937 rng(7);
    FusionOptions options;
    options.merge = merge;
    SceneFusion fusion(options);
    fusion.Integrate({SegmentOf(1, 1, Patch(0.0f, 1.0f, rng)),
                      SegmentOf(1, 2, Patch(1.0f, 2.0f, rng))},
                     0);
    ASSERT_EQ(fusion.segments().size(), 2u);
    for (size_t f = 1; f <= 4; ++f) {
      fusion.Integrate({SegmentOf(1, 1, Patch(0.7f, 1.3f, rng, 0.8f))}, f);
    }
    fusion.Finish();
    if (merge == FusionOptions::Merge::kPaper) {
      EXPECT_EQ(fusion.segments().size(), 3u);
      continue;
    }
    ASSERT_EQ(fusion.segments().size(), 1u);
    EXPECT_EQ(fusion.ResolveId(2), 1u);
    ASSERT_FALSE(fusion.events().empty());
    EXPECT_EQ(fusion.events().front().kind, FusionEvent::Kind::kEvidenceMerge);
    EXPECT_EQ(fusion.events().front().id, 2u);
    EXPECT_EQ(fusion.events().front().into, 1u);
    EXPECT_EQ(fusion.segments()[0].observations, 6u);
    // Both halves of view 0 are one sighting.
    EXPECT_EQ(fusion.segments()[0].frames_seen,
              (std::vector<uint32_t>{0, 1, 2, 3, 4}));
  }
}

// Two neighbours (a table and a chair pushed against it) that views show as
// separate masks: an occasional joint mask does not merge them.
TEST(FusionEvidence, NeighboursSeenApartStayApart) {
  std::mt19937 rng(8);
  SceneFusion fusion;
  uint32_t frame = 0;
  for (int k = 0; k < 5; ++k, ++frame) {
    fusion.Integrate({SegmentOf(1, 1, Patch(0.0f, 1.0f, rng)),
                      SegmentOf(1, 2, Patch(1.0f, 2.0f, rng))},
                     frame);
  }
  for (int k = 0; k < 2; ++k, ++frame) {
    fusion.Integrate({SegmentOf(1, 1, Patch(0.7f, 1.3f, rng, 0.8f))}, frame);
  }
  fusion.Finish();
  // one = 2 views, two = 4 views: 2 > 0.5 * 4 fails.
  EXPECT_EQ(fusion.ResolveId(1), 1u);
  EXPECT_EQ(fusion.ResolveId(2), 2u);
  const PairEvidence* e = fusion.evidence().Find(1, 2);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->one(), 2u);
  EXPECT_EQ(e->two(), 4u);  // views 1-4 (view 0 created them)
}

// One surface called class 1 in two views and class 2 in four: with evidence
// it is one object whose class is the vote (2); the paper's gating makes two.
TEST(FusionEvidence, ClassIsTheVoteOfEveryView) {
  for (const auto merge :
       {FusionOptions::Merge::kPaper, FusionOptions::Merge::kEvidence}) {
    std::mt19937 rng(9);
    FusionOptions options;
    options.merge = merge;
    SceneFusion fusion(options);
    const std::vector<uint16_t> classes = {1, 1, 2, 2, 2, 2};
    for (size_t f = 0; f < classes.size(); ++f) {
      fusion.Integrate({SegmentOf(classes[f], 1, Patch(0.0f, 1.0f, rng))}, f);
    }
    fusion.Finish();
    if (merge == FusionOptions::Merge::kPaper) {
      EXPECT_EQ(fusion.segments().size(), 2u);
      continue;
    }
    ASSERT_EQ(fusion.segments().size(), 1u);
    const SceneSegment& s = fusion.segments()[0];
    EXPECT_EQ(s.class_id, 2);
    ASSERT_EQ(s.class_votes.size(), 2u);
    const double share2 =
        static_cast<double>(s.class_votes.at(2)) /
        static_cast<double>(s.class_votes.at(1) + s.class_votes.at(2));
    EXPECT_NEAR(share2, 4.0 / 6.0, 0.05);  // four views of six, equal sizes
    // Class-2 segments lie on the class-1 object and join it until the vote
    // turns (after two or three of them, depending on the exact counts).
    size_t cross = 0;
    for (const FusionEvent& e : fusion.events()) {
      if (e.kind != FusionEvent::Kind::kCrossClassMatch) continue;
      ++cross;
      EXPECT_EQ(e.class_id, 2);
      EXPECT_EQ(e.into, 1u);
    }
    EXPECT_GE(cross, 2u);
    EXPECT_LE(cross, 3u);
  }
}

// The evidence rule's fragment clean-up (the voxel rule judges fragments by
// visibility instead: map_objects_test.cc).
FusionOptions EvidenceRule() {
  FusionOptions o;
  o.merge = FusionOptions::Merge::kEvidence;
  return o;
}

// A speck seen once beside an object of its class is folded into it; one far
// from anything is dropped; ids resolve accordingly.
TEST(FusionEvidence, FragmentsAreFoldedOrDropped) {
  std::mt19937 rng(10);
  SceneFusion fusion(EvidenceRule());
  for (size_t f = 0; f < 3; ++f) {
    fusion.Integrate({SegmentOf(1, 1, Patch(0.0f, 1.0f, rng))}, f);
  }
  Cloud far = Patch(0.0f, 0.1f, rng, 0.1f);
  for (auto& p : far) p.x() += 5.0f;
  fusion.Integrate(
      {SegmentOf(1, 2, Patch(1.0f, 1.12f, rng, 0.1f)), SegmentOf(1, 3, far)},
      3);
  ASSERT_EQ(fusion.segments().size(), 3u);
  EXPECT_EQ(fusion.Finish(), 2u);
  ASSERT_EQ(fusion.segments().size(), 1u);
  EXPECT_EQ(fusion.ResolveId(2), 1u);
  EXPECT_EQ(fusion.ResolveId(3), 0u);
  ASSERT_EQ(fusion.events().size(), 2u);
  // Smallest first: the far speck (10 x 10 cm) is dropped, then the one
  // beside the object (12 x 10 cm) folded into it.
  EXPECT_EQ(fusion.events()[0].kind, FusionEvent::Kind::kDropped);
  EXPECT_EQ(fusion.events()[0].id, 3u);
  EXPECT_EQ(fusion.events()[1].kind, FusionEvent::Kind::kFragmentMerge);
  EXPECT_EQ(fusion.events()[1].id, 2u);
  EXPECT_EQ(fusion.events()[1].into, 1u);
  // The paper's rule keeps everything.
  FusionOptions paper;
  paper.merge = FusionOptions::Merge::kPaper;
  SceneFusion p(paper);
  p.Integrate({SegmentOf(1, 3, far)}, 0);
  EXPECT_EQ(p.Finish(), 0u);
  EXPECT_EQ(p.segments().size(), 1u);
}

// Two masks of one view that fold together are still one sighting: the pair,
// far from anything else, is dropped.
TEST(FusionEvidence, MasksOfOneViewAreOneSighting) {
  std::mt19937 rng(11);
  SceneFusion fusion(EvidenceRule());
  Cloud left = Patch(0.0f, 0.1f, rng, 0.2f);
  Cloud right = Patch(0.1f, 0.25f, rng, 0.2f);
  fusion.Integrate({SegmentOf(1, 1, left), SegmentOf(1, 2, right)}, 0);
  ASSERT_EQ(fusion.segments().size(), 2u);
  EXPECT_EQ(fusion.Finish(), 2u);
  EXPECT_TRUE(fusion.segments().empty());
  ASSERT_EQ(fusion.events().size(), 2u);
  EXPECT_EQ(fusion.events()[0].kind, FusionEvent::Kind::kFragmentMerge);
  EXPECT_EQ(fusion.events()[1].kind, FusionEvent::Kind::kDropped);
  EXPECT_EQ(fusion.ResolveId(1), 0u);
  EXPECT_EQ(fusion.ResolveId(2), 0u);
}

}  // namespace
}  // namespace semrec::fuse
