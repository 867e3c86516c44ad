// The rules of objects decided per map voxel (fuse/map_objects.h), on
// synthetic surfaces that fail the way real labels do: structure classes on
// furniture near walls, objects seen in one view, parts seen once among many
// views, two objects joined in one mask.
#include "semrec/fuse/map_objects.h"

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "semrec/fuse/fusion.h"
#include "semrec/fuse/voxel_evidence.h"

namespace semrec::fuse {
namespace {

constexpr uint16_t kWall = 1, kFloor = 2, kChair = 3, kTable = 4, kSofa = 5,
                   kLamp = 6;

// Points on an axis-aligned box's surface (or a rectangle when one extent is
// zero), on a grid of `step_m`.
Cloud Box(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi,
          float step_m = 0.02f) {
  // Integer steps (a float loop counter drifts).
  const Eigen::Vector3i n = ((hi - lo) / step_m).array().round().cast<int>();
  Cloud c;
  for (int i = 0; i <= n.x(); ++i) {
    for (int j = 0; j <= n.y(); ++j) {
      for (int k = 0; k <= n.z(); ++k) {
        const bool surface = i == 0 || i == n.x() || j == 0 || j == n.y() ||
                             k == 0 || k == n.z();
        if (surface) c.push_back(lo + step_m * Eigen::Vector3f(i, j, k));
      }
    }
  }
  return c;
}

// The room: a wall at x = 0 and a floor at z = 0, 4 x 4 m.
Cloud WallPoints() { return Box({0, 0, 0.05f}, {0, 4, 2.5f}, 0.03f); }
Cloud FloorPoints() { return Box({0.05f, 0, 0}, {4, 4, 0}, 0.03f); }

FrameSegment Segment(uint16_t cls, uint16_t label, Cloud points) {
  FrameSegment s;
  s.class_id = cls;
  s.source_label = label;
  s.points_world = std::move(points);
  s.kind =
      cls == kWall || cls == kFloor ? ClassKind::kStuff : ClassKind::kThing;
  return s;
}

MapContext Context() {
  MapContext c;
  for (uint16_t id : {kWall, kFloor}) c.kinds[id] = ClassKind::kStuff;
  for (uint16_t id : {kChair, kTable, kSofa, kLamp}) {
    c.kinds[id] = ClassKind::kThing;
  }
  c.geometry[kWall] = StructureGeometry::kVertical;
  c.geometry[kFloor] = StructureGeometry::kFloor;
  return c;
}

struct View {
  std::vector<FrameSegment> segments;
  Cloud observed;  // besides the segments' own points
};

SceneFusion Fuse(const std::vector<View>& views, FusionOptions options = {}) {
  options.merge = FusionOptions::Merge::kVoxel;
  SceneFusion fusion(options);
  for (size_t i = 0; i < views.size(); ++i) {
    FrameObservation observation;
    observation.camera_position_world = {2.0f, 2.0f, 1.2f};
    observation.observed_world = views[i].observed;
    for (const FrameSegment& s : views[i].segments) {
      observation.observed_world.insert(observation.observed_world.end(),
                                        s.points_world.begin(),
                                        s.points_world.end());
    }
    fusion.Integrate(views[i].segments, i, &observation);
  }
  fusion.Finish();
  fusion.ResolveMap(Context());
  return fusion;
}

// Share of `points` lying within 3 cm of the segment's stored points, per
// object of the scene: where the ground-truth object's surface ended.
std::map<uint32_t, double> WhereItWent(const SceneFusion& fusion,
                                       const Cloud& points) {
  std::map<uint32_t, double> share;
  for (const Eigen::Vector3f& p : points) {
    uint32_t best = 0;
    float best_d2 = 0.03f * 0.03f;
    for (const SceneSegment& s : fusion.segments()) {
      for (const Eigen::Vector3f& q : s.points) {
        const float d2 = SquaredDistance(p, q);
        if (d2 < best_d2) best_d2 = d2, best = s.id;
      }
    }
    share[best] += 1.0 / static_cast<double>(points.size());
  }
  return share;
}

double ShareIn(const std::map<uint32_t, double>& went, uint32_t id) {
  const auto it = went.find(id);
  return it == went.end() ? 0.0 : it->second;
}

const SceneSegment* Largest(const SceneFusion& fusion, uint16_t cls) {
  const SceneSegment* best = nullptr;
  for (const SceneSegment& s : fusion.segments()) {
    if (s.class_id == cls && (!best || s.points.size() > best->points.size())) {
      best = &s;
    }
  }
  return best;
}

size_t Count(const SceneFusion& fusion, uint16_t cls) {
  return static_cast<size_t>(std::count_if(
      fusion.segments().begin(), fusion.segments().end(),
      [cls](const SceneSegment& s) { return s.class_id == cls; }));
}

TEST(MapObjects, ChairAgainstWallCalledWallInOneViewEndsAChair) {
  const Cloud chair = Box({0.08f, 1.0f, 0.1f}, {0.55f, 1.5f, 0.9f});
  std::vector<View> views;
  for (int i = 0; i < 4; ++i) {
    View v;
    v.segments.push_back(Segment(kWall, 1, WallPoints()));
    v.segments.push_back(Segment(kFloor, 2, FloorPoints()));
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

// A cabinet's front 15 cm before the wall, tall and wide enough to be a wall
// plane of its own, called wall in three views of four: no wall stands a
// hand's width in front of a larger one seen above it, so it is a cabinet.
TEST(MapObjects, FurnitureJustInFrontOfAWallIsNotWall) {
  const Cloud front = Box({0.15f, 1.0f, 0.0f}, {0.15f, 2.2f, 1.5f});
  const Cloud cabinet = Box({0.15f, 1.0f, 0.0f}, {0.55f, 2.2f, 1.5f});
  std::vector<View> views;
  for (int i = 0; i < 4; ++i) {
    View v;
    v.segments.push_back(Segment(kWall, 1, WallPoints()));
    v.segments.push_back(Segment(kFloor, 2, FloorPoints()));
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
  // Without the rule the front is a wall plane and stays wall.
  FusionOptions without;
  without.map_objects.planes.max_front_distance_m = 0.0;
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
    View v;
    v.segments.push_back(Segment(kWall, 1, WallPoints()));
    v.segments.push_back(Segment(kFloor, 2, FloorPoints()));
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
}

TEST(MapObjects, TwoChairsJoinedInOneViewAndApartInThreeEndAsTwo) {
  const Cloud a = Box({1.0f, 1.0f, 0.1f}, {1.45f, 1.45f, 0.9f});
  const Cloud b = Box({1.7f, 1.0f, 0.1f}, {2.15f, 1.45f, 0.9f});
  Cloud both = a;
  both.insert(both.end(), b.begin(), b.end());
  std::vector<View> views;
  for (int i = 0; i < 4; ++i) {
    View v;
    v.segments.push_back(Segment(kFloor, 1, FloorPoints()));
    if (i == 1) {
      v.segments.push_back(Segment(kChair, 2, both));
    } else {
      v.segments.push_back(Segment(kChair, 2, a));
      v.segments.push_back(Segment(kChair, 3, b));
    }
    views.push_back(std::move(v));
  }
  const SceneFusion fusion = Fuse(views);
  ASSERT_EQ(Count(fusion, kChair), 2u);
  const auto in_a = WhereItWent(fusion, a), in_b = WhereItWent(fusion, b);
  const auto top = [](const std::map<uint32_t, double>& m) {
    return std::max_element(m.begin(), m.end(),
                            [](auto x, auto y) { return x.second < y.second; });
  };
  EXPECT_GT(top(in_a)->second, 0.9);
  EXPECT_GT(top(in_b)->second, 0.9);
  EXPECT_NE(top(in_a)->first, top(in_b)->first);
}

// Two cabinets side by side, shown in separate masks by every view: the
// overlap rule fuses them (made eager here, as touching objects of one class
// often are), the views' masks cut them apart again.
TEST(MapObjects, NeighboursFusedByOverlapAreCutWhereTheViewsHeldThemApart) {
  const Cloud a = Box({1.0f, 1.0f, 0.0f}, {1.5f, 1.6f, 0.9f});
  const Cloud b = Box({1.56f, 1.0f, 0.0f}, {2.06f, 1.6f, 0.9f});
  std::vector<View> views;
  for (int i = 0; i < 3; ++i) {
    View v;
    v.segments.push_back(Segment(kFloor, 1, FloorPoints()));
    v.segments.push_back(Segment(kTable, 2, a));
    v.segments.push_back(Segment(kTable, 3, b));
    views.push_back(std::move(v));
  }
  FusionOptions eager;
  eager.alpha = 0.02;
  const SceneFusion fusion = Fuse(views, eager);
  ASSERT_EQ(Count(fusion, kTable), 2u);
  EXPECT_GE(fusion.map_resolution()->split_objects, 1u);
  const auto in_a = WhereItWent(fusion, a), in_b = WhereItWent(fusion, b);
  const auto top = [](const std::map<uint32_t, double>& m) {
    return *std::max_element(
        m.begin(), m.end(), [](auto x, auto y) { return x.second < y.second; });
  };
  EXPECT_GT(top(in_a).second, 0.9);
  EXPECT_GT(top(in_b).second, 0.9);
  EXPECT_NE(top(in_a).first, top(in_b).first);
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

// One view calls the whole chair table (its upper part is seen only there);
// three views show the lower part as chair. The parts are one object (held
// in one mask), and the class with more votes over both wins, not the class
// of the larger part.
TEST(MapObjects, ConfusedPartsJoinUnderTheClassWithMoreVotes) {
  const Cloud lower = Box({1.0f, 1.0f, 0.0f}, {1.5f, 1.5f, 0.4f});
  const Cloud upper = Box({1.0f, 1.0f, 0.42f}, {1.5f, 1.5f, 0.95f});
  Cloud chair = lower;
  chair.insert(chair.end(), upper.begin(), upper.end());
  std::vector<View> views(4);
  for (View& v : views) {
    v.segments.push_back(Segment(kFloor, 1, FloorPoints()));
  }
  views[0].segments.push_back(Segment(kTable, 2, chair));
  for (int i = 1; i < 4; ++i) {
    views[i].segments.push_back(Segment(kChair, 2, lower));
  }
  FusionOptions options;
  options.map_objects.confusion_share = 0.2;
  const SceneFusion fusion = Fuse(views, options);
  EXPECT_EQ(Count(fusion, kTable), 0u);
  ASSERT_EQ(Count(fusion, kChair), 1u);
  EXPECT_GT(WhereItWent(fusion, chair).at(Largest(fusion, kChair)->id), 0.9);
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
  FrameObservation near{{1.0f, 0.0f, 0.0f}, {}};
  map.AddFrame(
      {Segment(kChair, 1, Cloud(3, p)), Segment(kWall, 2, Cloud(1, p))}, {7, 8},
      &near, 0);
  FrameObservation far{{4.0f, 0.0f, 0.0f}, {p, {0.5f, 0.5f, 0.5f}}};
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
  FrameObservation near{{1.0f, 0.0f, 0.0f}, {}};
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
  EXPECT_EQ(StructureGeometryOf("wall"), StructureGeometry::kVertical);
  EXPECT_EQ(StructureGeometryOf("rug"), StructureGeometry::kFloor);
  EXPECT_EQ(StructureGeometryOf("sky"), StructureGeometry::kNone);
}

// A plane just in front of a larger wall (furniture) does not hold its
// points; one behind it (a recess), or in front of a stretch the wall does not
// cover, does.
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
      plane(0.0, 0.0, 4.0, 4000),   // the wall
      plane(0.15, 1.0, 2.0, 600),   // a cabinet's front
      plane(-0.3, 2.5, 3.0, 300),   // a recess behind the wall
      plane(0.15, 5.0, 6.0, 600)};  // beyond the wall's end
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
}

}  // namespace
}  // namespace semrec::fuse
