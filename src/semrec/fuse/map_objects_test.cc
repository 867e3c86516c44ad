// The rules of objects decided per map voxel (fuse/map_objects.h), on
// synthetic surfaces that fail the way real labels do: structure classes on
// furniture near walls, objects seen in one view, parts seen once among many
// views, two objects joined in one mask.
#include "semrec/fuse/map_objects.h"

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/fuse/fusion.h"
#include "semrec/fuse/map_test_util.h"
#include "semrec/fuse/voxel_votes.h"

namespace semrec::fuse {
namespace {

using namespace map_test;  // NOLINT(google-build-using-namespace)

TEST(MapObjects, ObjectSeenOnceInTheOnlyViewThatCoversItIsKept) {
  const Cloud sofa = Box({2.5f, 0.5f, 0.0f}, {3.5f, 1.3f, 0.8f});
  std::vector<View> views;
  for (int i = 0; i < 4; ++i) {
    View v;
    v.segments.push_back(Segment(kWall, 1, WallPoints()));
    if (i == 2) v.segments.push_back(Segment(kSofa, 2, sofa));
    views.push_back(std::move(v));
  }
  const SceneFusion fusion = Fuse(views);
  const SceneSegment* s = Largest(fusion, kSofa);
  ASSERT_NE(s, nullptr);
  EXPECT_GT(WhereItWent(fusion, sofa).at(s->id), 0.9);
  // The old rule dropped it (seen in one frame).
  FusionOptions evidence;
  evidence.merge = FusionOptions::Merge::kEvidence;
  SceneFusion old(evidence);
  for (size_t i = 0; i < views.size(); ++i) old.Integrate(views[i].segments, i);
  old.Finish();
  EXPECT_EQ(Count(old, kSofa), 0u);
}

TEST(MapObjects, PartSeenOnceWhereFiveViewsLookedIsAFragment) {
  const Cloud lamp = Box({2.0f, 3.0f, 0.0f}, {2.3f, 3.3f, 1.2f});
  std::vector<View> views;
  for (int i = 0; i < 5; ++i) {
    View v;
    v.segments.push_back(Segment(kWall, 1, WallPoints()));
    if (i == 0) {
      v.segments.push_back(Segment(kLamp, 2, lamp));
    } else {
      v.observed = lamp;  // seen, but no mask labelled it
    }
    views.push_back(std::move(v));
  }
  const SceneFusion fusion = Fuse(views);
  EXPECT_EQ(Count(fusion, kLamp), 0u);
  EXPECT_EQ(fusion.map_resolution()->fragments_dropped, 1u);
  // The ablation switch: without the fragment pass the lamp stays.
  FusionOptions without;
  without.map_objects.skip_passes = {"judge-fragments"};
  const SceneFusion kept = Fuse(views, without);
  EXPECT_EQ(Count(kept, kLamp), 1u);
  EXPECT_EQ(kept.map_resolution()->fragments_dropped, 0u);
}

TEST(MapObjects, PassesAreNamedInTheOrderTheyRunAndUnknownOnesRefused) {
  const std::vector<std::string>& names = MapResolverPassNames();
  ASSERT_EQ(names.size(), 12u);
  EXPECT_EQ(names.front(), "gate-structure");
  EXPECT_EQ(names.back(), "release-far-specks");
  const auto at = [&](const std::string& n) {
    return std::find(names.begin(), names.end(), n) - names.begin();
  };
  EXPECT_LT(at("split-by-masks"), at("merge-by-masks"));
  EXPECT_LT(at("merge-by-masks"), at("judge-fragments"));
  MapObjectOptions options;
  options.skip_passes = {"judge-fragments", "claim-enclosed"};
  EXPECT_NO_THROW(options.Check());
  options.skip_passes = {"judge-fragment"};
  try {
    options.Check();
    FAIL() << "an unknown pass was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("judge-fragment'"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("judge-fragments"), std::string::npos);
  }
}

// Surfaces `a` and `b` each ended mostly (> 90%) in one object, not the same.
void ExpectTwoWholeObjects(const SceneFusion& fusion, const Cloud& a,
                           const Cloud& b) {
  const auto in_a = WhereItWent(fusion, a), in_b = WhereItWent(fusion, b);
  EXPECT_GT(ShareIn(in_a, TopObject(in_a)), 0.9);
  EXPECT_GT(ShareIn(in_b, TopObject(in_b)), 0.9);
  EXPECT_NE(TopObject(in_a), TopObject(in_b));
}

TEST(MapObjects, TwoChairsJoinedInOneViewAndApartInThreeEndAsTwo) {
  const Cloud a = Box({1.0f, 1.0f, 0.1f}, {1.45f, 1.45f, 0.9f});
  const Cloud b = Box({1.7f, 1.0f, 0.1f}, {2.15f, 1.45f, 0.9f});
  Cloud both = a;
  both.insert(both.end(), b.begin(), b.end());
  std::vector<View> views =
      ViewsOf(4, {Segment(kChair, 2, a), Segment(kChair, 3, b)});
  views[1] = ViewsOf(1, {Segment(kChair, 2, both)})[0];
  const SceneFusion fusion = Fuse(views);
  ASSERT_EQ(Count(fusion, kChair), 2u);
  ExpectTwoWholeObjects(fusion, a, b);
}

// The kitchen case: two chairs whose only close view held both in one mask
// (it made them one fusion object), while three farther views held them apart
// but saw only the near third of the second chair. Cut by a far view, the
// rest of that chair has no mask but the joining one: it must not follow that
// mask into the first chair's piece (the pieces would then be two chairs and
// a third of one, which every view held in one mask with the rest).
TEST(MapObjects,
     TwoChairsJoinedByTheirOnlyCloseViewAreCutWhereFarViewsSawThem) {
  const Cloud a = Box({1.0f, 1.0f, 0.1f}, {1.45f, 1.45f, 0.9f});
  const Cloud b = Box({1.7f, 1.0f, 0.1f}, {2.15f, 1.45f, 0.9f});
  const Cloud b_near = Box({1.7f, 1.0f, 0.1f}, {1.85f, 1.45f, 0.9f});
  std::vector<View> views =
      ViewsOf(4, {Segment(kChair, 2, a), Segment(kChair, 3, b_near)});
  views[0] = ViewsOf(1, {Segment(kChair, 2, Join({a, b}))})[0];
  const SceneFusion fusion = Fuse(views);
  EXPECT_EQ(Count(fusion, kChair), 2u);
  ExpectTwoWholeObjects(fusion, a, b);
}

// As above, with the other side of the second chair seen by a fourth view
// whose mask bled onto the first chair's edge (a few voxels where the depths
// mix): that overlap does not carry the second chair's far side into the
// first chair's piece.
TEST(MapObjects, AFewVoxelsAMaskBledOntoAnotherChairDoNotCarryItsChairThere) {
  const Cloud a = Box({1.0f, 1.0f, 0.1f}, {1.45f, 1.45f, 0.9f});
  const Cloud b = Box({1.7f, 1.0f, 0.1f}, {2.15f, 1.45f, 0.9f});
  const Cloud b_near = Box({1.7f, 1.0f, 0.1f}, {1.85f, 1.45f, 0.9f});
  const Cloud b_far = Box({1.9f, 1.0f, 0.1f}, {2.15f, 1.45f, 0.9f});
  const Cloud a_edge = Box({1.45f, 1.2f, 0.5f}, {1.45f, 1.26f, 0.56f});
  std::vector<View> views =
      ViewsOf(3, {Segment(kChair, 2, a), Segment(kChair, 3, b_near)});
  views.insert(views.begin(),
               ViewsOf(1, {Segment(kChair, 2, Join({a, b}))})[0]);
  views.push_back(ViewsOf(1, {Segment(kChair, 4, Join({b_far, a_edge}))})[0]);
  const SceneFusion fusion = Fuse(views);
  ExpectTwoWholeObjects(fusion, a, b);
}

// Two chairs that three views held in separate masks, and between them a
// small piece of chair class (a bag on the floor, a coat) that only a fourth
// view saw, touching both: the piece may join either chair, but no chain of
// merges through it joins the chairs. Without that rule (and without the
// size rule, which also stops it: no view held the piece with either chair,
// and the two chairs are too large for one): one chair.
TEST(MapObjects, NoChainOfMergesJoinsTwoChairsTheViewsHeldApart) {
  const Cloud a = Box({1.0f, 1.0f, 0.1f}, {1.45f, 1.45f, 0.9f});
  const Cloud b = Box({1.75f, 1.0f, 0.1f}, {2.2f, 1.45f, 0.9f});
  const Cloud piece = Box({1.49f, 1.1f, 0.1f}, {1.71f, 1.35f, 0.3f});
  for (const size_t min_apart_views : {size_t{2}, size_t{1000}}) {
    std::vector<View> views =
        ViewsOf(3, {Segment(kChair, 2, a), Segment(kChair, 3, b)});
    views.push_back(ViewsOf(1, {Segment(kChair, 2, piece)})[0]);
    FusionOptions options;
    options.map_objects.min_apart_views = min_apart_views;
    if (min_apart_views > 2) options.map_objects.size_slack = 0.0;
    const SceneFusion fusion = Fuse(views, options);
    const uint32_t in_a = TopObject(WhereItWent(fusion, a));
    const uint32_t in_b = TopObject(WhereItWent(fusion, b));
    if (min_apart_views == 2) {
      EXPECT_EQ(Count(fusion, kChair), 2u);
      EXPECT_NE(in_a, in_b);
    } else {
      EXPECT_EQ(in_a, in_b) << "the chain joins them without the rule";
    }
  }
}

// A mask generator that cuts the same part off a chair in every view (the
// front rail under the seat, 5 cm in front of it): the small piece, nearly all
// of it touching the chair, is the chair's whatever the masks said. A box of
// the same class beside it, as large as the chair, stays its own object.
TEST(MapObjects, ASmallPieceEveryViewCutOffStaysWithTheObjectItTouches) {
  const Cloud chair = Box({1.0f, 1.0f, 0.1f}, {1.5f, 1.5f, 0.9f});
  const Cloud rail = Box({0.96f, 1.0f, 0.3f}, {0.96f, 1.5f, 0.45f});
  const Cloud other = Box({1.0f, 1.55f, 0.1f}, {1.5f, 2.05f, 0.9f});
  for (const double ratio : {0.25, 0.0}) {
    FusionOptions options;
    options.map_objects.max_attached_size_ratio = ratio;
    // (Chair and rail together also fit one chair: that rule off here.)
    options.map_objects.min_part_contact_share = 1.0;
    const SceneFusion fusion =
        Fuse(ViewsOf(4, {Segment(kChair, 2, chair), Segment(kChair, 3, rail),
                         Segment(kChair, 4, other)}),
             options);
    const uint32_t in_chair = TopObject(WhereItWent(fusion, chair));
    EXPECT_NE(in_chair, TopObject(WhereItWent(fusion, other))) << ratio;
    if (ratio > 0.0) {
      EXPECT_EQ(Count(fusion, kChair), 2u);
      EXPECT_EQ(TopObject(WhereItWent(fusion, rail)), in_chair);
    } else {
      EXPECT_EQ(Count(fusion, kChair), 3u) << "the rule is what joins it";
    }
  }
}

// A mask generator that cuts a sofa's back off its seat in every view: the
// two pieces, joined along a seam and together no larger than a sofa, are
// one sofa. Two chairs side by side, touching, that every view held apart
// stay two: together they are too long for one chair. Two tables side by
// side are no longer than one long table, but too wide for one.
TEST(MapObjects, PartsEveryViewCutApartAreOneObjectIfTogetherTheyFitOne) {
  const Cloud seat = Box({1.0f, 1.0f, 0.0f}, {1.9f, 3.0f, 0.42f});
  const Cloud back = Box({1.0f, 1.0f, 0.44f}, {1.2f, 3.0f, 0.82f});
  const Cloud chair_a = Box({2.5f, 1.0f, 0.0f}, {2.95f, 1.45f, 0.9f});
  const Cloud chair_b = Box({2.98f, 1.0f, 0.0f}, {3.43f, 1.45f, 0.9f});
  const Cloud table_a = Box({2.4f, 2.0f, 0.0f}, {3.3f, 3.4f, 0.74f});
  const Cloud table_b = Box({3.32f, 2.0f, 0.0f}, {4.22f, 3.4f, 0.74f});
  for (const double share : {0.05, 1.0}) {
    FusionOptions options;
    options.map_objects.min_part_contact_share = share;
    const SceneFusion fusion = Fuse(
        ViewsOf(4, {Segment(kSofa, 2, seat), Segment(kSofa, 3, back),
                    Segment(kChair, 4, chair_a), Segment(kChair, 5, chair_b),
                    Segment(kTable, 6, table_a), Segment(kTable, 7, table_b)}),
        options);
    EXPECT_EQ(Count(fusion, kSofa), share < 1.0 ? 1u : 2u) << share;
    EXPECT_EQ(Count(fusion, kChair), 2u) << share;
    EXPECT_EQ(Count(fusion, kTable), 2u) << share;
  }
}

// A mask generator that cuts a bookcase's boards off its frame in every view:
// the boards lie inside the frame's box, and objects do not interpenetrate,
// so they are one bookcase (a class of no known size: the fit rule cannot
// tell). A second bookcase beside it, touching, stays its own.
TEST(MapObjects, PiecesInsideEachOthersBoxAreOneObjectWhateverTheViewsSaid) {
  Cloud frame = Box({1.0f, 1.0f, 0.0f}, {1.36f, 1.03f, 1.8f});
  const Cloud right = Box({1.0f, 1.87f, 0.0f}, {1.36f, 1.9f, 1.8f});
  frame.insert(frame.end(), right.begin(), right.end());
  Cloud boards;
  for (const float z : {0.4f, 0.8f, 1.2f}) {
    const Cloud board = Box({1.0f, 1.05f, z}, {1.36f, 1.85f, z});
    boards.insert(boards.end(), board.begin(), board.end());
  }
  const Cloud other = Box({1.0f, 1.92f, 0.0f}, {1.36f, 2.82f, 1.8f});
  for (const double share : {0.5, 0.0}) {
    FusionOptions options;
    options.map_objects.min_nested_share = share;
    const SceneFusion fusion =
        Fuse(ViewsOf(4, {Segment(kShelf, 2, frame), Segment(kShelf, 3, boards),
                         Segment(kShelf, 4, other)}),
             options);
    const uint32_t in_frame = TopObject(WhereItWent(fusion, frame));
    EXPECT_NE(in_frame, TopObject(WhereItWent(fusion, other))) << share;
    if (share > 0.0) {
      EXPECT_EQ(Count(fusion, kShelf), 2u);
      EXPECT_EQ(TopObject(WhereItWent(fusion, boards)), in_frame);
    } else {
      EXPECT_EQ(Count(fusion, kShelf), 3u) << "the rule is what joins them";
    }
  }
}

// Two cabinets side by side (a class of no known size, so no size rule joins
// them), shown in separate masks by every view: the overlap rule fuses them
// (made eager here, as touching objects of one class often are), the views'
// masks cut them apart again.
TEST(MapObjects, NeighboursFusedByOverlapAreCutWhereTheViewsHeldThemApart) {
  const Cloud a = Box({1.0f, 1.0f, 0.0f}, {1.5f, 1.6f, 0.9f});
  const Cloud b = Box({1.56f, 1.0f, 0.0f}, {2.06f, 1.6f, 0.9f});
  FusionOptions eager;
  eager.alpha = 0.02;
  const SceneFusion fusion =
      Fuse(ViewsOf(3, {Segment(kShelf, 2, a), Segment(kShelf, 3, b)}), eager);
  ASSERT_EQ(Count(fusion, kShelf), 2u);
  EXPECT_GE(fusion.map_resolution()->split_objects, 1u);
  ExpectTwoWholeObjects(fusion, a, b);
}

// A mask generator cuts one object far more often than it joins two: a
// chair cut into seat and back by one of two views stays one chair, even
// when fusion was eager.
TEST(MapObjects, AChairCutByOneOfTwoViewsStaysOneChair) {
  const Cloud seat = Box({1.0f, 1.0f, 0.0f}, {1.5f, 1.5f, 0.45f});
  const Cloud back = Box({1.0f, 1.42f, 0.47f}, {1.5f, 1.5f, 1.0f});
  Cloud chair = seat;
  chair.insert(chair.end(), back.begin(), back.end());
  for (const double alpha : {0.5, 0.02}) {
    std::vector<View> views(2);
    for (View& v : views) {
      v.segments.push_back(Segment(kFloor, 1, FloorPoints()));
    }
    views[0].segments.push_back(Segment(kChair, 2, seat));
    views[0].segments.push_back(Segment(kChair, 3, back));
    views[1].segments.push_back(Segment(kChair, 2, chair));
    FusionOptions options;
    options.alpha = alpha;
    const SceneFusion fusion = Fuse(views, options);
    EXPECT_EQ(Count(fusion, kChair), 1u) << "alpha " << alpha;
    const SceneSegment* c = Largest(fusion, kChair);
    ASSERT_NE(c, nullptr);
    EXPECT_GT(WhereItWent(fusion, chair).at(c->id), 0.9);
  }
}

// A box cut in two where coordinate `axis` equals `cut`: the two parts'
// surfaces, without the cut face (inside the object).
std::pair<Cloud, Cloud> CutBox(const Eigen::Vector3f& lo,
                               const Eigen::Vector3f& hi, int axis, float cut) {
  std::pair<Cloud, Cloud> parts;
  for (const Eigen::Vector3f& p : Box(lo, hi)) {
    if (std::abs(p[axis] - cut) < 0.005f) continue;
    (p[axis] < cut ? parts.first : parts.second).push_back(p);
  }
  return parts;
}

// One view held a sofa's two halves apart; another, close up, saw a strip
// across the middle in one mask, most of it on the right half (fusion joined
// that strip to the right half only). One view against one, touching: one
// sofa. Without the tie rule: two.
TEST(MapObjects, ASofaHeldWholeByOneViewAndCutByAnotherIsOneSofa) {
  const auto [left, right] =
      CutBox({1.0f, 1.0f, 0.0f}, {3.0f, 1.8f, 0.8f}, 0, 2.0f);
  Cloud strip;
  for (const Cloud* c : {&left, &right}) {
    for (const Eigen::Vector3f& p : *c) {
      if (p.x() > 1.85f && p.x() < 2.45f) strip.push_back(p);
    }
  }
  for (const bool tie_rule : {true, false}) {
    std::vector<View> views(2, RoomView());
    views[0].segments.push_back(Segment(kSofa, 3, left));
    views[0].segments.push_back(Segment(kSofa, 4, right));
    views[1].segments.push_back(Segment(kSofa, 3, strip));
    FusionOptions options;
    if (!tie_rule) options.map_objects.min_tie_contact_voxels = 100000;
    const SceneFusion fusion = Fuse(views, options);
    EXPECT_EQ(Count(fusion, kSofa), tie_rule ? 1u : 2u) << tie_rule;
  }
}

// Chairs `a` and `b` end as two whole chairs with the size rule (size_slack
// 1.25), as one without it (size_slack 0).
void ExpectTwoChairsByTheSizeRule(const std::vector<View>& views,
                                  const Cloud& a, const Cloud& b) {
  for (const double slack : {1.25, 0.0}) {
    FusionOptions options;
    options.map_objects.size_slack = slack;
    const SceneFusion fusion = Fuse(views, options);
    if (slack > 0.0) {
      EXPECT_EQ(Count(fusion, kChair), 2u);
      ExpectTwoWholeObjects(fusion, a, b);
    } else {
      EXPECT_EQ(Count(fusion, kChair), 1u) << "one without the size rule";
    }
  }
}

// 3DMatch's lounge: chairs side by side, each seen in its own masks by
// some views and never with the other. Touching and of one class used to be
// enough to join them; together they are no chair (0.95 m, a chair at most
// 0.75), so two chairs. A table seen in halves by different views is still
// one table: together its halves fit one.
TEST(MapObjects, ChairsSideBySideNoViewSawTogetherStayTwo) {
  const Cloud a = Box({1.0f, 1.0f, 0.1f}, {1.45f, 1.45f, 0.9f});
  const Cloud b = Box({1.5f, 1.0f, 0.1f}, {1.95f, 1.45f, 0.9f});
  std::vector<View> views = ViewsOf(2, {Segment(kChair, 2, a)});
  for (const View& v : ViewsOf(2, {Segment(kChair, 2, b)})) {
    views.push_back(v);
  }
  ExpectTwoChairsByTheSizeRule(views, a, b);
  const Cloud left = Box({1.0f, 1.0f, 0.7f}, {1.9f, 1.8f, 0.75f});
  const Cloud right = Box({1.95f, 1.0f, 0.7f}, {2.8f, 1.8f, 0.75f});
  std::vector<View> table_views = ViewsOf(2, {Segment(kTable, 2, left)});
  for (const View& v : ViewsOf(2, {Segment(kTable, 2, right)})) {
    table_views.push_back(v);
  }
  const SceneFusion tables = Fuse(table_views);
  EXPECT_EQ(Count(tables, kTable), 1u);
}

// One view's mask held two chairs 1 m apart (a mask over a row of chairs,
// the chairs nearer the camera apart in depth), the others saw each alone:
// pieces that do not touch stay one object when a view held them in one
// mask, unless together they are too large for one of their class. A table
// whose middle a box hid from every view stays one.
TEST(MapObjects, PiecesOneMaskHeldStayOneOnlyWhenTheyFitOneObject) {
  const Cloud a = Box({1.0f, 1.0f, 0.1f}, {1.45f, 1.45f, 0.9f});
  const Cloud b = Box({2.5f, 1.0f, 0.1f}, {2.95f, 1.45f, 0.9f});
  std::vector<View> views = ViewsOf(1, {Segment(kChair, 2, Join({a, b}))});
  for (const View& v : ViewsOf(2, {Segment(kChair, 2, a)})) views.push_back(v);
  for (const View& v : ViewsOf(2, {Segment(kChair, 2, b)})) views.push_back(v);
  ExpectTwoChairsByTheSizeRule(views, a, b);
  const Cloud left = Box({1.0f, 1.0f, 0.7f}, {1.6f, 1.8f, 0.75f});
  const Cloud right = Box({2.2f, 1.0f, 0.7f}, {2.8f, 1.8f, 0.75f});
  const SceneFusion table =
      Fuse(ViewsOf(3, {Segment(kTable, 2, Join({left, right}))}));
  EXPECT_EQ(Count(table, kTable), 1u);
  const auto in_left = WhereItWent(table, left);
  EXPECT_GT(ShareIn(WhereItWent(table, right), TopObject(in_left)), 0.9);
}

// One view's mask over a chair also caught a few points 1.2 m away (3DMatch:
// a chair's mesh stretched to 2.4 x 2.3 m by such specks). A speck far from
// the rest of its object leaves it: it joins what it touches (here a table)
// or is dropped; a speck near the object stays with it, and so does one
// with which the object still fits its class (a table's, 0.45 m off).
TEST(MapObjects, FarSpecksLeaveTheirObject) {
  const Cloud chair = Box({1.0f, 1.0f, 0.1f}, {1.45f, 1.45f, 0.9f});
  const Cloud far = Box({2.5f, 1.1f, 0.81f}, {2.54f, 1.14f, 0.85f});
  const Cloud near = Box({1.6f, 1.1f, 0.5f}, {1.64f, 1.14f, 0.54f});
  const Cloud table = Box({2.2f, 0.8f, 0.7f}, {3.0f, 1.6f, 0.75f});
  for (const double gap : {0.3, 0.0}) {
    FusionOptions options;
    options.map_objects.max_speck_gap_m = gap;
    SCOPED_TRACE(gap);
    // The far speck alone in the air, and on a table of its own masks.
    for (const bool on_table : {false, true}) {
      std::vector<FrameSegment> segments = {
          Segment(kChair, 2, Join({chair, far, near}))};
      if (on_table) segments.push_back(Segment(kTable, 3, table));
      const SceneFusion fusion = Fuse(ViewsOf(3, segments), options);
      const uint32_t id = TopObject(WhereItWent(fusion, chair));
      // (Shares of points within 3 cm of the objects' 5 cm points: a 4 cm
      // speck's corners fall outside.)
      EXPECT_GT(ShareIn(WhereItWent(fusion, near), id), 0.5);
      const auto went = WhereItWent(fusion, far);
      ASSERT_NE(fusion.map_resolution(), nullptr);
      EXPECT_EQ(fusion.map_resolution()->far_specks_moved, gap > 0.0 ? 1u : 0u);
      if (gap == 0.0) {
        EXPECT_GT(ShareIn(went, id), 0.5) << "the rule off: it stays";
        continue;
      }
      EXPECT_EQ(ShareIn(went, id), 0.0);
      if (on_table) {
        EXPECT_GT(ShareIn(went, TopObject(WhereItWent(fusion, table))), 0.5);
      } else {
        EXPECT_GT(ShareIn(went, 0), 0.9) << "dropped";
      }
    }
  }
  const Cloud off_table = Box({3.45f, 1.1f, 0.7f}, {3.49f, 1.14f, 0.74f});
  const SceneFusion fusion =
      Fuse(ViewsOf(3, {Segment(kTable, 3, Join({table, off_table}))}));
  EXPECT_GT(ShareIn(WhereItWent(fusion, off_table),
                    TopObject(WhereItWent(fusion, table))),
            0.5);
  EXPECT_EQ(fusion.map_resolution()->far_specks_moved, 0u);
  // With the size rules off (size_slack 0) no object of a class of known
  // size is too large: the chair keeps its far speck.
  FusionOptions no_sizes;
  no_sizes.map_objects.size_slack = 0.0;
  const SceneFusion chairs = Fuse(
      ViewsOf(3, {Segment(kChair, 2, Join({chair, far, near}))}), no_sizes);
  EXPECT_EQ(chairs.map_resolution()->far_specks_moved, 0u);
}

TEST(VoxelEvidence, EachViewKeepsTheMaskHoldingMostOfAVoxel) {
  VoxelEvidenceMap map(0.05, {});
  const Eigen::Vector3f p(0.01f, 0.01f, 0.01f);
  // View 0: 3 pixels of mask 4, 1 of mask 5 (the neighbour's depth mixing
  // in at the contact), 6 of the wall (a structure mask: not kept).
  map.AddFrame(
      {Segment(kChair, 4, Cloud(3, p)), Segment(kChair, 5, Cloud(1, p)),
       Segment(kWall, 1, Cloud(6, p))},
      {7, 8, 9}, nullptr, 0);
  map.AddFrame({Segment(kChair, 5, Cloud(2, p))}, {8}, nullptr, 1);
  map.AddFrame({Segment(kWall, 1, Cloud(2, p))}, {9}, nullptr, 2);
  const VoxelEvidence& v = map.voxels().at(VoxelKey(p, 20.0f));
  EXPECT_EQ(v.masks, (std::vector<uint64_t>{MaskId(0, 4), MaskId(1, 5)}));
  EXPECT_EQ(v.views, 3u);
}

TEST(VoxelEvidence, OneVotePerViewSplitOverClassesAndWeightedByDistance) {
  VoxelEvidenceMap map(0.05, {});
  // Voxel (0,0,0): 3 chair pixels and 1 wall pixel in a view 1 m away, then
  // 10 wall pixels in a view 4 m away.
  const Eigen::Vector3f p(0.01f, 0.01f, 0.01f);
  FrameObservation near{{1.0f, 0.0f, 0.0f}, {}, {}};
  map.AddFrame(
      {Segment(kChair, 1, Cloud(3, p)), Segment(kWall, 2, Cloud(1, p))}, {7, 8},
      &near, 0);
  FrameObservation far{{4.0f, 0.0f, 0.0f}, {p, {0.5f, 0.5f, 0.5f}}, {}};
  map.AddFrame({Segment(kWall, 1, Cloud(10, p))}, {8}, &far, 1);
  const VoxelEvidence& v = map.voxels().at(VoxelKey(p, 20.0f));
  EXPECT_EQ(v.views, 2u);
  EXPECT_EQ(v.points, 14u);
  ASSERT_NE(v.Find(kChair), nullptr);
  EXPECT_NEAR(v.Find(kChair)->weight, 0.75f, 1e-5);
  EXPECT_EQ(v.Find(kChair)->views, 1u);
  EXPECT_NEAR(v.Find(kWall)->weight, 0.25f + 2.0f / 3.99f, 1e-4);
  EXPECT_EQ(v.Find(kWall)->views, 1u);  // only the far view's majority
  // The far view also observed an unlabelled voxel.
  EXPECT_EQ(map.voxels().at(VoxelKey({0.5f, 0.5f, 0.5f}, 20.0f)).views, 1u);
  EXPECT_EQ(map.labelled_voxels(), 1u);
}

TEST(VoxelEvidence, UnsureMasksCastLessThanAVote) {
  VoxelEvidenceMap map(0.05, {});
  const Eigen::Vector3f p(0.01f, 0.01f, 0.01f);
  FrameObservation near{{1.0f, 0.0f, 0.0f}, {}, {}};
  // View 0: the chair mask at confidence 0.55 (3 pixels), a wall pixel at 1.
  FrameSegment chair = Segment(kChair, 1, Cloud(3, p));
  chair.confidence = 0.55f;
  map.AddFrame({chair, Segment(kWall, 2, Cloud(1, p))}, {7, 8}, &near, 0);
  // View 1: all wall, unsure (0.4).
  FrameSegment wall = Segment(kWall, 1, Cloud(4, p));
  wall.confidence = 0.4f;
  map.AddFrame({wall}, {8}, &near, 1);
  const VoxelEvidence& v = map.voxels().at(VoxelKey(p, 20.0f));
  EXPECT_NEAR(v.Find(kChair)->weight, 0.75f * 0.55f, 1e-5);
  EXPECT_NEAR(v.Find(kWall)->weight, 0.25f + 0.4f, 1e-5);
  // Views count by pixel majority, whatever the confidence.
  EXPECT_EQ(v.Find(kChair)->views, 1u);
  EXPECT_EQ(v.Find(kWall)->views, 1u);
}

// A 1 x 1 m upright square at x = 0 (y -0.5..0.5, z 0.5..1.5), as one view
// 1 m away ranged it (class `cls`).
VoxelEvidenceMap SquareMap(uint16_t cls, const VoxelEvidenceOptions& options,
                           const Cloud& more = {}) {
  VoxelEvidenceMap map(0.05, options);
  FrameObservation near{{1.0f, 0.0f, 1.0f}, {}, {}};
  std::vector<FrameSegment> segments = {
      Segment(cls, 1, Box({0, -0.5f, 0.5f}, {0, 0.5f, 1.5f}))};
  std::vector<uint32_t> ids = {7};
  if (!more.empty())
    segments.push_back(Segment(kChair, 2, more)), ids.push_back(8);
  map.AddFrame(segments, ids, &near, 0);
  return map;
}

void AddFarView(VoxelEvidenceMap* map, const FarView& far, size_t frame) {
  FrameObservation o;
  o.camera_position_world = far.T_world_camera.translation().cast<float>();
  o.far = far;
  map->AddFrame({}, {}, &o, frame);
}

const std::vector<ClassEvidence>* VotesAt(
    const std::unordered_map<uint64_t, VoxelEvidenceMap::FarEvidence>& votes,
    const Eigen::Vector3f& p) {
  const auto it = votes.find(VoxelKey(p, 20.0f));
  return it == votes.end() ? nullptr : &it->second.classes;
}

TEST(VoxelEvidence, FarViewsVoteOnWhatTheirSensorCouldNotRange) {
  // A view 6 m away whose sensor ranged 4 m sees the square, calls it shelf
  // and gives no depth there: one full vote on every voxel it shows.
  const auto all_shelf = [](int, int) { return kShelf; };
  VoxelEvidenceMap map = SquareMap(kLamp, {});
  AddFarView(&map, FarViewAlongMinusX({6, 0, 1}, 4.0f, all_shelf), 1);
  auto votes = map.FarVotes();
  EXPECT_EQ(votes.size(), map.labelled_voxels());
  const auto* centre = VotesAt(votes, {0.01f, 0.01f, 1.01f});
  ASSERT_NE(centre, nullptr);
  ASSERT_EQ(centre->size(), 1u);
  EXPECT_EQ((*centre)[0].class_id, kShelf);
  EXPECT_NEAR((*centre)[0].weight, 1.0f, 1e-5);
  EXPECT_EQ((*centre)[0].views, 1u);

  // Within the view's reach the missing depth says something (a dark or
  // shiny surface, an edge): no vote.
  map = SquareMap(kLamp, {});
  AddFarView(&map, FarViewAlongMinusX({6, 0, 1}, 7.0f, all_shelf), 1);
  EXPECT_TRUE(map.FarVotes().empty());
  VoxelEvidenceOptions off;
  off.far_views = false;
  map = SquareMap(kLamp, off);
  AddFarView(&map, FarViewAlongMinusX({6, 0, 1}, 4.0f, all_shelf), 1);
  EXPECT_TRUE(map.FarVotes().empty());

  // A nearer surface (a chair at x = 2 before the square's y < 0 half)
  // takes the votes there; the square behind it gets none.
  map = SquareMap(kLamp, {}, Box({2, -0.5f, 0.5f}, {2, -0.05f, 1.5f}));
  AddFarView(&map, FarViewAlongMinusX({6, 0, 1}, 3.5f, all_shelf), 1);
  votes = map.FarVotes();
  EXPECT_EQ(VotesAt(votes, {0.01f, -0.29f, 1.01f}), nullptr);
  EXPECT_NE(VotesAt(votes, {2.01f, -0.29f, 1.01f}), nullptr);
  EXPECT_NE(VotesAt(votes, {0.01f, 0.31f, 1.01f}), nullptr);

  // Cells on a border between classes (image x 320: world y 0) do not vote;
  // each side votes its own class.
  map = SquareMap(kLamp, {});
  AddFarView(
      &map,
      FarViewAlongMinusX({6, 0, 1}, 4.0f,
                         [](int x, int) { return x < 320 ? kShelf : kTable; }),
      1);
  votes = map.FarVotes();
  const auto* left = VotesAt(votes, {0.01f, -0.29f, 1.01f});
  const auto* right = VotesAt(votes, {0.01f, 0.31f, 1.01f});
  ASSERT_NE(left, nullptr);
  ASSERT_NE(right, nullptr);
  EXPECT_EQ(left->size(), 1u);
  EXPECT_EQ(left->front().class_id, kShelf);
  EXPECT_EQ(right->size(), 1u);
  EXPECT_EQ(right->front().class_id, kTable);
  EXPECT_EQ(VotesAt(votes, {0.01f, 0.01f, 1.01f}), nullptr);
}

}  // namespace
}  // namespace semrec::fuse
