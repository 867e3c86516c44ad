// The structure rules of objects decided per map voxel (fuse/map_objects.h,
// fuse/structure_planes.h), on synthetic surfaces that fail the way real labels
// do: furniture near walls called wall, legs called floor, the parts of a
// thing flush with the wall, the two faces of an interior wall (furniture
// fronts: furniture_front_test.cc).
#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "semrec/fuse/fusion.h"
#include "semrec/fuse/map_objects.h"
#include "semrec/fuse/map_test_util.h"
#include "semrec/fuse/structure_planes.h"

namespace semrec::fuse {
namespace {

using namespace map_test;  // NOLINT(google-build-using-namespace)

TEST(MapObjects, ChairAgainstWallCalledWallInOneViewEndsAChair) {
  const Cloud chair = Box({0.08f, 1.0f, 0.1f}, {0.55f, 1.5f, 0.9f});
  std::vector<View> views;
  for (int i = 0; i < 4; ++i) {
    View v = RoomView();
    // View 0 paints the whole chair as wall (a joined wall mask).
    if (i == 0) {
      v.segments[0].points_world.insert(v.segments[0].points_world.end(),
                                        chair.begin(), chair.end());
    } else {
      v.segments.push_back(Segment(kChair, 3, chair));
    }
    views.push_back(std::move(v));
  }
  const SceneFusion fusion = Fuse(views);
  const SceneSegment* c = Largest(fusion, kChair);
  ASSERT_NE(c, nullptr);
  const auto went = WhereItWent(fusion, chair);
  EXPECT_GT(went.at(c->id), 0.9);
  const SceneSegment* wall = Largest(fusion, kWall);
  ASSERT_NE(wall, nullptr);
  EXPECT_LT(went.count(wall->id) ? went.at(wall->id) : 0.0, 0.05);
  EXPECT_EQ(Count(fusion, kChair), 1u);
  // Paper rule: the wall keeps what it swallowed.
}

// Every view calls a chair's legs floor (a 2D model's classic bleed): off the
// floor plane nothing else voted there, so the gate alone cannot move them;
// they join the chair they touch. A raised platform every view calls floor,
// larger than the box beside it, stays floor; so does a patch of floor seen
// again 25 cm up (drift) that meets a larger table along one edge only, and a
// raised strip under a thin board, touching it along half its width but
// larger than the board.
TEST(MapObjects, LegsEveryViewCalledFloorJoinTheChairTheyTouch) {
  const Cloud legs = Box({1.0f, 1.0f, 0.1f}, {1.45f, 1.45f, 0.3f});
  const Cloud seat = Box({1.0f, 1.0f, 0.32f}, {1.45f, 1.45f, 0.9f});
  const Cloud platform = Box({2.5f, 2.5f, 0.4f}, {3.5f, 3.5f, 0.4f});
  const Cloud box = Box({3.52f, 2.9f, 0.0f}, {3.8f, 3.2f, 0.5f});
  const Cloud drifted = Box({0.5f, 2.6f, 0.25f}, {1.6f, 3.2f, 0.25f});
  const Cloud table = Box({1.62f, 2.3f, 0.0f}, {2.4f, 3.5f, 0.75f});
  const Cloud board = Box({2.0f, 0.5f, 0.3f}, {2.0f, 2.0f, 0.6f});
  const Cloud strip = Box({1.75f, 0.5f, 0.2f}, {2.25f, 2.0f, 0.2f});
  std::vector<View> views;
  for (int i = 0; i < 3; ++i) {
    View v;
    v.segments.push_back(Segment(kWall, 1, WallPoints()));
    Cloud floor = FloorPoints();
    floor.insert(floor.end(), legs.begin(), legs.end());
    floor.insert(floor.end(), platform.begin(), platform.end());
    floor.insert(floor.end(), drifted.begin(), drifted.end());
    floor.insert(floor.end(), strip.begin(), strip.end());
    v.segments.push_back(Segment(kFloor, 2, floor));
    v.segments.push_back(Segment(kChair, 3, seat));
    v.segments.push_back(Segment(kTable, 4, box));
    v.segments.push_back(Segment(kTable, 5, table));
    v.segments.push_back(Segment(kLamp, 6, board));
    views.push_back(std::move(v));
  }
  FusionOptions without;
  without.map_objects.claim_stranded = false;
  for (const bool claim : {true, false}) {
    const SceneFusion fusion = Fuse(views, claim ? FusionOptions{} : without);
    const SceneSegment* chair = Largest(fusion, kChair);
    const SceneSegment* floor = Largest(fusion, kFloor);
    ASSERT_NE(chair, nullptr);
    ASSERT_NE(floor, nullptr);
    const double in_chair = ShareIn(WhereItWent(fusion, legs), chair->id);
    EXPECT_EQ(Count(fusion, kChair), 1u);
    if (claim) {
      EXPECT_GT(in_chair, 0.8);
      EXPECT_GT(fusion.map_resolution()->stranded_voxels_claimed, 20u);
    } else {
      EXPECT_LT(in_chair, 0.2);
    }
    EXPECT_GT(ShareIn(WhereItWent(fusion, platform), floor->id), 0.9)
        << "claim " << claim;
    EXPECT_GT(ShareIn(WhereItWent(fusion, drifted), floor->id), 0.9)
        << "claim " << claim;
    EXPECT_GT(ShareIn(WhereItWent(fusion, strip), floor->id), 0.9)
        << "claim " << claim;
  }
}

// A low board every view calls floor, along a chair's side and smaller than
// it, is no part of the chair: chair and board together are 1.1 m long, more
// than one chair can be (kitchen 2: a counter every view called wall joined the
// plant beside it, a 2.5 m "plant"). The legs of another chair, called floor
// too, still join it.
TEST(MapObjects, StrandedStructureDoesNotMakeAThingTooLargeForItsClass) {
  const Cloud seat = Box({1.0f, 1.0f, 0.32f}, {1.45f, 1.45f, 0.9f});
  const Cloud legs = Box({1.0f, 1.0f, 0.1f}, {1.45f, 1.45f, 0.3f});
  const Cloud chair = Box({2.5f, 2.5f, 0.1f}, {2.95f, 2.95f, 0.9f});
  const Cloud bench = Box({2.97f, 2.5f, 0.1f}, {3.05f, 3.6f, 0.45f});
  std::vector<View> views;
  for (int i = 0; i < 3; ++i) {
    View v;
    v.segments.push_back(Segment(kWall, 1, WallPoints()));
    v.segments.push_back(
        Segment(kFloor, 2, Join({FloorPoints(), legs, bench})));
    v.segments.push_back(Segment(kChair, 3, seat));
    v.segments.push_back(Segment(kChair, 4, chair));
    views.push_back(std::move(v));
  }
  const SceneFusion fusion = Fuse(views);
  const SceneSegment* floor = Largest(fusion, kFloor);
  ASSERT_NE(floor, nullptr);
  EXPECT_EQ(Count(fusion, kChair), 2u);
  const auto bench_went = WhereItWent(fusion, bench);
  const auto chair_went = WhereItWent(fusion, chair);
  const uint32_t chair_id = TopObject(chair_went);
  EXPECT_LT(ShareIn(bench_went, chair_id),
            0.2);  // its face 2 cm from the chair's
  EXPECT_GT(ShareIn(bench_went, floor->id), 0.8);
  const auto legs_went = WhereItWent(fusion, legs);
  EXPECT_GT(ShareIn(legs_went, TopObject(WhereItWent(fusion, seat))), 0.8);
}

// A low unit every view calls wall, off the wall's plane, between a table
// along its side and a tall shelf at its end: nearest to the table, most of
// it would make the table too large for one, so that share goes to the shelf
// (kitchen 2: a counter's top every view called wall, beside a table and a
// counter) instead of staying wall. (A shelf smaller than the share would
// not take it: larger than every thing left to take it, more likely
// structure.)
TEST(MapObjects, StrandedStructureATooSmallThingCannotTakeGoesToAnother) {
  const Cloud unit = Box({0.6f, 1.0f, 0.05f}, {2.6f, 1.6f, 0.6f});
  const Cloud table = Box({0.6f, 1.64f, 0.05f}, {2.6f, 2.9f, 0.75f});
  const Cloud shelf = Box({2.64f, 1.0f, 0.05f}, {3.4f, 1.6f, 1.8f});
  // Three views: the unit called wall, the table, and `end_class` at its end.
  const auto fuse = [&](uint16_t end_class, const Cloud& at_end) {
    std::vector<View> views;
    for (int i = 0; i < 3; ++i) {
      View v = RoomView();
      v.segments.push_back(Segment(kWall, 3, unit));
      v.segments.push_back(Segment(kTable, 4, table));
      v.segments.push_back(Segment(end_class, 5, at_end));
      views.push_back(std::move(v));
    }
    return Fuse(views);
  };
  const SceneFusion fusion = fuse(kShelf, shelf);
  const auto went = WhereItWent(fusion, unit);
  const SceneSegment* s = Largest(fusion, kShelf);
  const SceneSegment* t = Largest(fusion, kTable);
  ASSERT_NE(s, nullptr);
  ASSERT_NE(t, nullptr);
  EXPECT_GT(ShareIn(went, s->id), 0.8);
  EXPECT_LT(ShareIn(went, t->id), 0.05);
  EXPECT_GT(ShareIn(WhereItWent(fusion, table), t->id), 0.9);
  // A chair at the unit's end instead: it keeps the end nearest to it though
  // it cannot take the table's share too (the claim goes in rounds, a share
  // that fits is kept).
  const Cloud chair = Box({2.64f, 1.0f, 0.05f}, {3.09f, 1.45f, 0.9f});
  // The unit's top near its end, nearer the chair than the table.
  const Cloud end = Box({2.35f, 1.0f, 0.6f}, {2.55f, 1.3f, 0.6f});
  const SceneFusion chaired = fuse(kChair, chair);
  const SceneSegment* c = Largest(chaired, kChair);
  const SceneSegment* t2 = Largest(chaired, kTable);
  ASSERT_NE(c, nullptr);
  ASSERT_NE(t2, nullptr);
  EXPECT_GT(ShareIn(WhereItWent(chaired, end), c->id), 0.5);
  EXPECT_LT(ShareIn(WhereItWent(chaired, unit), c->id), 0.3);
  EXPECT_LT(ShareIn(WhereItWent(chaired, unit), t2->id), 0.05);
}

// A cabinet's front 15 cm before the wall, tall and wide enough to be a wall
// plane of its own, called wall in three views of four: no wall stands a
// hand's width in front of a larger one seen above it, so it is a cabinet.
TEST(MapObjects, FurnitureJustInFrontOfAWallIsNotWall) {
  const Cloud front = Box({0.15f, 1.0f, 0.0f}, {0.15f, 2.2f, 1.5f});
  const Cloud cabinet = Box({0.15f, 1.0f, 0.0f}, {0.55f, 2.2f, 1.5f});
  std::vector<View> views;
  for (int i = 0; i < 4; ++i) {
    View v = RoomView();
    if (i == 3) {
      v.segments.push_back(Segment(kTable, 3, cabinet));
    } else {
      v.segments[0].points_world.insert(v.segments[0].points_world.end(),
                                        front.begin(), front.end());
    }
    views.push_back(std::move(v));
  }
  const SceneFusion fusion = Fuse(views);
  const SceneSegment* c = Largest(fusion, kTable);
  ASSERT_NE(c, nullptr);
  EXPECT_GT(WhereItWent(fusion, front).at(c->id), 0.9);
  EXPECT_EQ(Count(fusion, kTable), 1u);
  // Without the rule the front is a wall plane and stays wall (the flush
  // rule, which would take it by its table vote, off too).
  FusionOptions without;
  without.map_objects.planes.max_furniture_depth_m = 0.0;
  without.map_objects.min_flush_share = 1.0;
  const SceneFusion old = Fuse(views, without);
  const SceneSegment* wall = Largest(old, kWall);
  ASSERT_NE(wall, nullptr);
  EXPECT_GT(WhereItWent(old, front).at(wall->id), 0.9);
}

TEST(MapObjects, WallVotesOffTheWallPlaneDoNotCount) {
  // A table 30 cm from the wall: called wall in three of four views, table in
  // one. Off every large vertical plane the wall votes are set aside.
  const Cloud table = Box({0.3f, 2.0f, 0.1f}, {1.1f, 2.8f, 0.75f});
  std::vector<View> views;
  for (int i = 0; i < 4; ++i) {
    View v = RoomView();
    v.segments.push_back(Segment(i == 3 ? kTable : kWall, 3, table));
    views.push_back(std::move(v));
  }
  const SceneFusion fusion = Fuse(views);
  const SceneSegment* t = Largest(fusion, kTable);
  ASSERT_NE(t, nullptr);
  EXPECT_GT(WhereItWent(fusion, table).at(t->id), 0.9);
  ASSERT_NE(fusion.map_resolution(), nullptr);
  EXPECT_GT(fusion.map_resolution()->gated_voxels, 100u);
}

TEST(StructurePlanes, WallsAreLargeVerticalPlanesAndTheFloorTheLowest) {
  Cloud walls = Box({0, 0, 0}, {0, 4, 2.5f}, 0.05f);
  const Cloud other = Box({0, 4, 0}, {3, 4, 2.5f}, 0.05f);
  walls.insert(walls.end(), other.begin(), other.end());
  const Cloud small = Box({2, 1, 0}, {2, 1.5f, 0.5f}, 0.05f);  // 0.25 m2
  walls.insert(walls.end(), small.begin(), small.end());
  const auto planes = FindStructurePlanes(walls, StructureGeometry::kVertical,
                                          Eigen::Vector3d::UnitZ(), 0.0025, {});
  ASSERT_EQ(planes.size(), 2u);
  EXPECT_TRUE(OnAnyPlane({0.01f, 2, 1}, planes, 0.06));
  EXPECT_TRUE(OnAnyPlane({1.5f, 3.98f, 1}, planes, 0.06));
  EXPECT_FALSE(OnAnyPlane({2, 1.2f, 0.2f}, planes, 0.06));

  Cloud floors = Box({0, 0, 0}, {3, 3, 0}, 0.05f);
  const Cloud table_top = Box({1, 1, 0.75f}, {2, 2, 0.75f}, 0.05f);
  floors.insert(floors.end(), table_top.begin(), table_top.end());
  const auto floor = FindStructurePlanes(floors, StructureGeometry::kFloor,
                                         Eigen::Vector3d::UnitZ(), 0.0025, {});
  ASSERT_EQ(floor.size(), 1u);
  EXPECT_NEAR(floor[0].offset, 0.0, 0.01);
  EXPECT_FALSE(OnAnyPlane({1.5f, 1.5f, 0.75f}, floor, 0.06));
}

// A plane just in front of a larger wall (furniture) does not hold its
// points, up to a worktop's depth (a counter's front 0.65 m before the wall,
// kitchen 4); one further (0.9 m), behind it (a recess), or in front of a
// stretch the wall does not cover, does.
TEST(StructurePlanes, NoWallStandsJustInFrontOfALargerOne) {
  const auto plane = [](double x, double y0, double y1, size_t support) {
    StructurePlane p;
    p.geometry = StructureGeometry::kVertical;
    p.normal = -Eigen::Vector3d::UnitX();  // oriented below
    p.offset = -x;
    p.support = support;
    p.along = Eigen::Vector3d::UnitY();
    for (double y = y0; y < y1; y += 0.1) {
      p.along_bins.push_back(static_cast<int64_t>(std::floor(y / 0.1 + 1e-9)));
    }
    return p;
  };
  std::vector<StructurePlane> planes = {
      plane(0.0, 0.0, 4.0, 4000),  // the wall
      plane(0.15, 1.0, 2.0, 600),  // a cabinet's front
      plane(-0.3, 2.5, 3.0, 300),  // a recess behind the wall
      plane(0.15, 5.0, 6.0, 600),  // beyond the wall's end
      plane(0.65, 1.0, 2.0, 600),  // a worktop's front
      plane(0.9, 1.0, 2.0, 600)};  // deeper than furniture
  // The room lies at x > 0.
  OrientToInterior(Box({0.5f, 0, 0}, {4, 4, 2.5f}, 0.1f), 0.06, &planes);
  EXPECT_GT(planes[0].normal.x(), 0.9);
  const StructurePlaneOptions o;
  EXPECT_TRUE(OnStructure({0.01f, 1.5f, 1}, planes, o));
  EXPECT_FALSE(OnStructure({0.15f, 1.5f, 1}, planes, o));
  EXPECT_TRUE(OnAnyPlane({0.15f, 1.5f, 1}, planes, o.tolerance_m));
  EXPECT_TRUE(OnStructure({-0.3f, 2.7f, 1}, planes, o));
  EXPECT_TRUE(OnStructure({0.15f, 5.5f, 1}, planes, o));
  EXPECT_FALSE(OnStructure({1.0f, 1.5f, 1}, planes, o));
  EXPECT_FALSE(OnStructure({0.65f, 1.5f, 0.5f}, planes, o));
  EXPECT_TRUE(OnStructure({0.9f, 1.5f, 0.5f}, planes, o));
  StructurePlaneOptions shallow = o;
  shallow.max_furniture_depth_m = 0.6;
  EXPECT_TRUE(OnStructure({0.65f, 1.5f, 0.5f}, planes, shallow));
  EXPECT_FALSE(OnStructure({0.15f, 1.5f, 1}, planes, shallow));
}

// A sofa's back stands flush with the wall, 3-6 cm in front of it: within a
// 6 cm tolerance (a wall measured less well than this one, whose own
// tolerance is 2.5 cm), so the plane cannot tell it from the wall. Three
// views near the wall call it wall, one calls it sofa with the rest of the
// sofa: it joins the sofa it touches. A patch of the wall one view called
// sofa, touching no sofa, stays wall.
TEST(MapObjects, TheBackOfASofaFlushWithTheWallJoinsTheSofa) {
  const Cloud back = Box({0.03f, 1.0f, 0.0f}, {0.06f, 2.5f, 0.9f});
  const Cloud seat = Box({0.08f, 1.0f, 0.0f}, {0.9f, 2.5f, 0.45f});
  auto in_patch = [](const Eigen::Vector3f& p) {
    return p.y() > 3.2f && p.y() < 3.8f && p.z() > 1.4f && p.z() < 2.0f;
  };
  std::vector<View> views;
  for (int i = 0; i < 4; ++i) {
    View v;
    Cloud wall, patch;
    for (const Eigen::Vector3f& p : WallPoints()) {
      (i == 3 && in_patch(p) ? patch : wall).push_back(p);
    }
    if (i < 3) wall.insert(wall.end(), back.begin(), back.end());
    v.segments.push_back(Segment(kWall, 1, wall));
    v.segments.push_back(Segment(kFloor, 2, FloorPoints()));
    Cloud sofa = seat;
    if (i == 3) sofa.insert(sofa.end(), back.begin(), back.end());
    v.segments.push_back(Segment(kSofa, 3, sofa));
    if (i == 3) v.segments.push_back(Segment(kSofa, 4, patch));
    views.push_back(std::move(v));
  }
  Cloud patch;
  for (const Eigen::Vector3f& p : WallPoints()) {
    if (in_patch(p)) patch.push_back(p);
  }
  for (const bool rule : {true, false}) {
    SCOPED_TRACE(rule ? "with the rule" : "without");
    FusionOptions options;
    options.map_objects.planes.min_tolerance_m = 0.06;
    if (!rule) options.map_objects.min_flush_share = 1.0;
    const SceneFusion fusion = Fuse(views, options);
    const SceneSegment* sofa = Largest(fusion, kSofa);
    const SceneSegment* wall = Largest(fusion, kWall);
    ASSERT_NE(sofa, nullptr);
    ASSERT_NE(wall, nullptr);
    const auto went = WhereItWent(fusion, back);
    if (rule) {
      EXPECT_GT(ShareIn(went, sofa->id), 0.8);
    } else {
      EXPECT_LT(ShareIn(went, sofa->id), 0.4);
    }
    EXPECT_GT(ShareIn(WhereItWent(fusion, patch), wall->id), 0.9);
  }
}

// 7-Scenes chess: the top of a partition, behind its face's plane, some views
// called cabinet, and so did a quarter of the views of the face below it. The
// face stays wall: flush parts grow only from things in front of the wall.
TEST(MapObjects, AWallBelowAThingBehindItStaysWall) {
  const Cloud top = Box({-0.12f, 1.0f, 2.5f}, {-0.02f, 2.0f, 2.5f});
  auto in_patch = [](const Eigen::Vector3f& p) {
    return p.y() >= 1.0f && p.y() <= 2.0f && p.z() > 1.9f;
  };
  std::vector<View> views;
  for (int i = 0; i < 4; ++i) {
    View v;
    Cloud wall, patch;
    for (const Eigen::Vector3f& p : WallPoints()) {
      (i == 3 && in_patch(p) ? patch : wall).push_back(p);
    }
    v.segments.push_back(Segment(kWall, 1, wall));
    v.segments.push_back(Segment(kFloor, 2, FloorPoints()));
    Cloud cabinet = top;
    cabinet.insert(cabinet.end(), patch.begin(), patch.end());
    v.segments.push_back(Segment(kTable, 3, cabinet));
    views.push_back(std::move(v));
  }
  Cloud patch;
  for (const Eigen::Vector3f& p : WallPoints()) {
    if (in_patch(p) && p.z() < 2.4f) patch.push_back(p);
  }
  const SceneFusion fusion = Fuse(views);
  const SceneSegment* wall = Largest(fusion, kWall);
  ASSERT_NE(wall, nullptr);
  ASSERT_NE(Largest(fusion, kTable), nullptr);
  EXPECT_GT(ShareIn(WhereItWent(fusion, patch), wall->id), 0.9);
}

// The floor is flat: its own tolerance follows the spread of its voxels'
// heights. The foot of a cabinet every view called floor, 5-10 cm up, is off
// a flat floor (and joins the cabinet it belongs to), but within the fixed
// 6 cm tolerance.
TEST(MapObjects, TheFootOfACabinetCalledFloorLeavesAFlatFloor) {
  const Cloud foot = Box({1.0f, 1.0f, 0.0f}, {1.6f, 1.8f, 0.1f});
  const Cloud body = Box({1.0f, 1.0f, 0.12f}, {1.6f, 1.8f, 0.9f});
  std::vector<View> views;
  for (int i = 0; i < 3; ++i) {
    View v;
    v.segments.push_back(Segment(kWall, 1, WallPoints()));
    Cloud floor = FloorPoints();
    floor.insert(floor.end(), foot.begin(), foot.end());
    v.segments.push_back(Segment(kFloor, 2, floor));
    v.segments.push_back(Segment(kTable, 3, body));
    views.push_back(std::move(v));
  }
  Cloud band;  // the foot's sides 6-8 cm up (its top voxel layer)
  for (const Eigen::Vector3f& p : foot) {
    if (p.z() > 0.05f && p.z() < 0.095f) band.push_back(p);
  }
  for (const bool own : {true, false}) {
    SCOPED_TRACE(own ? "own tolerance" : "fixed 6 cm");
    FusionOptions options;
    if (!own) options.map_objects.planes.min_tolerance_m = 0.06;
    const SceneFusion fusion = Fuse(views, options);
    const SceneSegment* cabinet = Largest(fusion, kTable);
    const SceneSegment* floor = Largest(fusion, kFloor);
    ASSERT_NE(cabinet, nullptr);
    ASSERT_NE(floor, nullptr);
    const auto went = WhereItWent(fusion, band);
    EXPECT_GT(ShareIn(went, own ? cabinet->id : floor->id), 0.5);
  }
}

// A plane has its own tolerance: 4 x its points' robust spread (1.4826 x
// MAD), between 2.5 and 6 cm. A floor or a wall measured well is thin: the
// foot of a cabinet 4 cm up, a headboard 4 cm in front, is not on it. One
// whose points lie +-3 cm about it (7 levels) keeps the 6 cm.
TEST(StructurePlanes, APlanesToleranceFollowsItsSpread) {
  struct Case {
    const char* name;
    Cloud flat;
    int normal_axis;
    StructureGeometry geometry;
  };
  for (const Case& c : {Case{"floor", Box({0, 0, 0}, {3, 3, 0}, 0.05f), 2,
                             StructureGeometry::kFloor},
                        Case{"wall", Box({0, 0, 0}, {0, 4, 2.5f}, 0.05f), 0,
                             StructureGeometry::kVertical}}) {
    SCOPED_TRACE(c.name);
    Cloud rough = c.flat;
    for (size_t i = 0; i < rough.size(); ++i) {
      rough[i][c.normal_axis] =
          0.03f * static_cast<float>(static_cast<int>(i % 7) - 3) / 3;
    }
    const StructurePlaneOptions o;
    const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
    const auto a = FindStructurePlanes(c.flat, c.geometry, up, 0.0025, o);
    const auto b = FindStructurePlanes(rough, c.geometry, up, 0.0025, o);
    ASSERT_EQ(a.size(), 1u);
    ASSERT_EQ(b.size(), 1u);
    EXPECT_DOUBLE_EQ(a[0].tolerance_m, o.min_tolerance_m);
    EXPECT_DOUBLE_EQ(b[0].tolerance_m, o.tolerance_m);  // 4 sigma > 6 cm
    const auto at = [&](float d) {  // 1 m into the plane, d off it
      Eigen::Vector3f p(1, 1, 1);
      p[c.normal_axis] = d;
      return p;
    };
    EXPECT_TRUE(OnStructure(at(0.02f), a, o));
    EXPECT_FALSE(OnStructure(at(0.04f), a, o));
    EXPECT_TRUE(OnStructure(at(0.05f), b, o));
  }
}

// An interior wall 10 cm thick seen from both rooms: two faces, each seen
// from its own side. With the views' directions they are two planes facing
// their rooms; without, one plane holds both faces (and a headboard 5 cm in
// front of either face is within its tolerance).
TEST(StructurePlanes, TheTwoFacesOfAnInteriorWallAreTwoPlanes) {
  const Cloud a = Box({3.95f, 0, 0}, {3.95f, 5, 2.5f}, 0.05f);
  const Cloud b = Box({4.05f, 0, 0}, {4.05f, 5, 2.5f}, 0.05f);
  Cloud both = a;
  both.insert(both.end(), b.begin(), b.end());
  std::vector<Eigen::Vector3f> towards(a.size(), {-1, 0, 0});
  towards.resize(both.size(), {1, 0, 0});
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  const auto sided = FindStructurePlanes(both, StructureGeometry::kVertical, up,
                                         0.0025, {}, towards);
  ASSERT_EQ(sided.size(), 2u);
  for (const StructurePlane& p : sided) {
    EXPECT_TRUE(p.oriented);
    EXPECT_EQ(p.support, a.size());
    // Facing the room it was seen from: -x for the face at 3.95.
    const double x = p.offset / p.normal.x();
    EXPECT_NEAR(x, p.normal.x() < 0 ? 3.95 : 4.05, 0.005);
  }
  const auto blind =
      FindStructurePlanes(both, StructureGeometry::kVertical, up, 0.0025, {});
  ASSERT_FALSE(blind.empty());
  EXPECT_GT(blind[0].support, a.size());  // tilted through both faces
}

// Behind a wall is inside it or on top of it, unless in front of the wall's
// other face: the next room.
TEST(StructurePlanes, BehindAWallIsNotTheNextRoom) {
  const Cloud a = Box({3.95f, 0, 0}, {3.95f, 5, 2.5f}, 0.05f);
  const Cloud b = Box({4.05f, 0, 0}, {4.05f, 5, 2.5f}, 0.05f);
  Cloud both = a;
  both.insert(both.end(), b.begin(), b.end());
  std::vector<Eigen::Vector3f> towards(a.size(), {-1, 0, 0});
  towards.resize(both.size(), {1, 0, 0});
  const StructurePlaneOptions o;
  const auto two =
      FindStructurePlanes(both, StructureGeometry::kVertical,
                          Eigen::Vector3d::UnitZ(), 0.0025, o, towards);
  const auto one = FindStructurePlanes(a, StructureGeometry::kVertical,
                                       Eigen::Vector3d::UnitZ(), 0.0025, o,
                                       {a.size(), {-1, 0, 0}});
  ASSERT_EQ(two.size(), 2u);
  ASSERT_EQ(one.size(), 1u);
  EXPECT_FALSE(BehindWall({4.3f, 2, 1}, two, o));  // the next room
  EXPECT_TRUE(BehindWall({4.3f, 2, 1}, one, o));   // its far face unseen
  EXPECT_FALSE(BehindWall({3.5f, 2, 1}, two, o));  // in front
  EXPECT_FALSE(BehindWall({4.8f, 2, 1}, one, o));  // farther than 60 cm
}

// Sparse views: of the two views that saw a plant and the chair beside it,
// one held both in the chair's mask (a third saw the plant alone): a third
// of the plant's votes say chair. Objects of different classes merge only
// when most views that saw both held them in one mask: the plant stays.
TEST(MapObjects, APlantJoinedToAChairInOneOfTwoViewsStaysAPlant) {
  const Cloud chair = Box({1.0f, 1.0f, 0.0f}, {1.45f, 1.45f, 0.9f});
  const Cloud plant = Box({1.52f, 1.0f, 0.0f}, {1.95f, 1.4f, 0.8f});
  std::vector<View> views;
  for (int i = 0; i < 3; ++i) {
    View v = RoomView();
    Cloud c = chair;
    if (i == 0) c.insert(c.end(), plant.begin(), plant.end());
    if (i < 2) v.segments.push_back(Segment(kChair, 3, c));
    if (i > 0) v.segments.push_back(Segment(kLamp, 4, plant));
    views.push_back(std::move(v));
  }
  const SceneFusion fusion = Fuse(views);
  const SceneSegment* p = Largest(fusion, kLamp);
  ASSERT_NE(p, nullptr);
  EXPECT_GT(ShareIn(WhereItWent(fusion, plant), p->id), 0.8);
  EXPECT_EQ(Count(fusion, kChair), 1u);
}

// The other side of the same rule: a sofa seen whole in one view and cut in
// the other, its end called plant there. One view says one, one says two, and
// nearly half the end's votes say sofa: one sofa.
TEST(MapObjects, ASofaWholeInOneViewAndCutInTheOtherStaysOneSofa) {
  const Cloud body = Box({1.0f, 1.0f, 0.0f}, {1.9f, 2.4f, 0.8f});
  const Cloud end = Box({1.0f, 2.46f, 0.0f}, {1.9f, 3.0f, 0.8f});
  std::vector<View> views;
  for (int i = 0; i < 2; ++i) {
    View v = RoomView();
    Cloud sofa = body;
    if (i == 0) sofa.insert(sofa.end(), end.begin(), end.end());
    v.segments.push_back(Segment(kSofa, 3, sofa));
    if (i == 1) v.segments.push_back(Segment(kLamp, 4, end));
    // The whole view from farther away: its votes weigh less (44% sofa).
    if (i == 0) v.camera = {3.5f, 4.0f, 1.2f};
    views.push_back(std::move(v));
  }
  const SceneFusion fusion = Fuse(views);
  const SceneSegment* sofa = Largest(fusion, kSofa);
  ASSERT_NE(sofa, nullptr);
  EXPECT_GT(ShareIn(WhereItWent(fusion, end), sofa->id), 0.8);
  EXPECT_EQ(Count(fusion, kLamp), 0u);
  // A majority of views alone would leave the end a lamp.
  FusionOptions majority;
  majority.map_objects.tie_confusion_share = 1.0;
  EXPECT_EQ(Count(Fuse(views, majority), kLamp), 1u);
}

// A floor measured too poorly for a plane (Bonn crowd, 4-5 m away, spreads
// over 0.9 m of height): its one plane holds a fifth of it. Gated, the floor
// off that plane was stranded and joined the large thing lying on it (a shelf
// fallen flat, 5 cm above, touching all of it: Bonn's things, bloated by
// people, touched half the stranded structure). Not gated, it stays floor.
TEST(MapObjects, AFloorNoPlaneHoldsIsNotGated) {
  const auto bent = [](float x) { return 0.15f * x * x; };  // 0 to 2.4 m up
  Cloud floor, shelf, raised;
  for (int i = 0; i <= 100; ++i) {
    for (int j = 0; j <= 50; ++j) {
      const float x = 0.04f * static_cast<float>(i);
      const float y = 0.04f * static_cast<float>(j);
      floor.emplace_back(x, y, bent(x));
      if (x >= 1.6f) raised.emplace_back(x, y, bent(x));
      if (x >= 1.2f) shelf.emplace_back(x, y, bent(x) + 0.05f);
    }
  }
  View view;
  view.segments = {Segment(kFloor, 1, floor), Segment(kShelf, 2, shelf)};
  const std::vector<View> views(3, view);
  const auto raised_in_shelf = [&](const FusionOptions& options) {
    const SceneFusion fusion = Fuse(views, options);
    const SceneSegment* s = Largest(fusion, kShelf);
    return s == nullptr ? 0.0 : ShareIn(WhereItWent(fusion, raised), s->id);
  };
  // (11%: where the floor is steep the shelf 5 cm above lies within the 3 cm
  // WhereItWent looks.)
  EXPECT_LT(raised_in_shelf({}), 0.25);
  FusionOptions gated;
  gated.map_objects.min_structure_on_planes = 0.0;
  EXPECT_GT(raised_in_shelf(gated), 0.75);  // the shelf took it (94%)
}

}  // namespace
}  // namespace semrec::fuse
