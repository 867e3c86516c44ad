// Surface normals from depth (SurfaceNormalAt), their agreement per map voxel
// (VoxelEvidence::SurfaceAxis) and the rule they serve: a surface turned away
// from a structure plane is not on it, however close it lies.
#include <algorithm>
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "semrec/fuse/map_test_util.h"
#include "semrec/fuse/segments.h"
#include "semrec/fuse/voxel_votes.h"

namespace semrec::fuse {
namespace {

using namespace map_test;  // NOLINT(build/namespaces)

double AngleDeg(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  const double c = std::clamp(
      static_cast<double>(a.normalized().dot(b.normalized())), -1.0, 1.0);
  return std::acos(c) * 180.0 / std::numbers::pi;
}

// Depth of the plane n . p = d (camera frame) along each pixel's ray.
DepthImage PlaneDepth(const CameraIntrinsics& k, const Eigen::Vector3d& n,
                      double d) {
  DepthImage depth(k.width, k.height);
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const Eigen::Vector3d ray = k.BackProject(u, v, 1.0);
      depth(u, v) = static_cast<float>(d / n.dot(ray));
    }
  }
  return depth;
}

TEST(SurfaceNormals, APlanesNormalFacesTheCameraWhateverTheStep) {
  // At 0.11 degrees a pixel, a surface turned up to ~80 degrees from the ray
  // changes depth by less than 10 % over a dozen pixels.
  const CameraIntrinsics k = Kinect();
  // A plane turned 40 degrees about the camera's y axis, 2 m ahead.
  const double a = 40.0 * std::numbers::pi / 180.0;
  const Eigen::Vector3d n(std::sin(a), 0.0, std::cos(a));
  const DepthImage depth = PlaneDepth(k, n, 2.0);
  // Facing the camera: against the view direction (+z).
  const Eigen::Vector3f expected = -n.cast<float>();
  for (int step : {1, 3, 12}) {
    for (const auto& [u, v] : {std::pair{320, 240}, std::pair{0, 0},
                               std::pair{639, 479}, std::pair{50, 400}}) {
      const Eigen::Vector3f got = SurfaceNormalAt(depth, k, u, v, step);
      EXPECT_NEAR(got.norm(), 1.0f, 1e-5f);
      EXPECT_LT(AngleDeg(got, expected), 0.5)
          << u << "," << v << " step " << step;
    }
  }
}

TEST(SurfaceNormals, DepthJumpsAndHolesAreLeftOut) {
  const CameraIntrinsics k = Kinect();
  // A wall 3 m ahead, facing the camera; the left half a box 1 m ahead whose
  // face is tilted 30 degrees.
  DepthImage depth = PlaneDepth(k, Eigen::Vector3d::UnitZ(), 3.0);
  const double a = 30.0 * std::numbers::pi / 180.0;
  const Eigen::Vector3d box_n(0.0, std::sin(a), std::cos(a));
  const DepthImage box = PlaneDepth(k, box_n, 1.0);
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < 320; ++u) depth(u, v) = box(u, v);
  }
  // At the box's edge the neighbours across the jump do not count: each side
  // keeps its own surface's normal.
  EXPECT_LT(
      AngleDeg(SurfaceNormalAt(depth, k, 319, 200, 3), -box_n.cast<float>()),
      0.5);
  EXPECT_LT(AngleDeg(SurfaceNormalAt(depth, k, 320, 200, 3),
                     -Eigen::Vector3f::UnitZ()),
            0.5);
  // No depth, or no neighbour on one image axis: no normal.
  depth(100, 100) = 0.0f;
  EXPECT_EQ(SurfaceNormalAt(depth, k, 100, 100, 3), Eigen::Vector3f::Zero());
  DepthImage lone(k.width, k.height);
  lone(40, 30) = 2.0f;
  lone(43, 30) = 2.0f;  // a neighbour along u only
  EXPECT_EQ(SurfaceNormalAt(lone, k, 40, 30, 3), Eigen::Vector3f::Zero());
}

TEST(SurfaceNormals, AVoxelsAxisNeedsAgreeingNormalsEnough) {
  VoxelEvidence v;
  Eigen::Vector3f axis;
  EXPECT_FALSE(v.SurfaceAxis(0.6f, 10.0f, &axis));  // none measured
  // A board seen from both sides: opposite normals, one axis.
  for (int i = 0; i < 12; ++i) {
    const Eigen::Vector3f n =
        (i % 2 == 0 ? 1.0f : -1.0f) *
        Eigen::Vector3f(0.05f * static_cast<float>(i % 3), 1.0f, 0.0f)
            .normalized();
    v.normal_scatter += n * n.transpose();
  }
  ASSERT_TRUE(v.SurfaceAxis(0.6f, 10.0f, &axis));
  EXPECT_LT(AngleDeg(axis.cwiseAbs(), Eigen::Vector3f::UnitY()), 5.0);
  EXPECT_FALSE(v.SurfaceAxis(0.6f, 20.0f, &axis));  // too few
  // A corner: as many normals along x as along y: no axis.
  for (int i = 0; i < 12; ++i) {
    v.normal_scatter +=
        Eigen::Vector3f::UnitX() * Eigen::Vector3f::UnitX().transpose();
  }
  EXPECT_FALSE(v.SurfaceAxis(0.6f, 10.0f, &axis));
}

// `points` with the same normal everywhere (what SurfaceNormalAt gives a
// flat surface).
FrameSegment Facing(FrameSegment s, const Eigen::Vector3f& normal) {
  s.normals_world.assign(s.points_world.size(), normal);
  return s;
}

// A shelf against the wall (x = 0): two side boards and three shelves 36 cm
// deep; every view calls its rear 20 cm wall (a 2D model at the contact).
// The rear voxels lie within the wall plane's tolerance, but their surfaces
// run into the wall, not along it: they join the shelf, and the wall keeps its
// own voxels. Without normals they stay wall.
TEST(MapObjects, BoardsRunningIntoTheWallAreNotWall) {
  const float depth_m = 0.36f, rear_m = 0.2f;
  auto sides = [](float x0, float x1) {
    return Join({Box({x0, 1.5f, 0.05f}, {x1, 1.5f, 1.8f}),
                 Box({x0, 2.4f, 0.05f}, {x1, 2.4f, 1.8f})});
  };
  auto shelves = [](float x0, float x1) {
    return Join({Box({x0, 1.53f, 0.6f}, {x1, 2.37f, 0.6f}),
                 Box({x0, 1.53f, 1.2f}, {x1, 2.37f, 1.2f}),
                 Box({x0, 1.53f, 1.8f}, {x1, 2.37f, 1.8f})});
  };
  const Cloud rear_sides = sides(0.02f, rear_m);
  const Cloud rear_shelves = shelves(0.02f, rear_m);
  Cloud wall = WallPoints();
  // The wall behind the shelf is hidden.
  std::erase_if(wall, [](const Eigen::Vector3f& p) {
    return p.y() > 1.49f && p.y() < 2.41f && p.z() < 1.81f;
  });
  auto views = [&](bool normals) {
    std::vector<View> out;
    for (int i = 0; i < 4; ++i) {
      View v;
      v.camera = {2.5f, 1.0f + 0.5f * static_cast<float>(i), 1.4f};
      FrameSegment w = Segment(kWall, 1, wall);
      FrameSegment rs = Segment(kWall, 1, rear_sides);
      FrameSegment rb = Segment(kWall, 1, rear_shelves);
      if (normals) {
        w = Facing(w, Eigen::Vector3f::UnitX());
        rs = Facing(rs, Eigen::Vector3f::UnitY());
        rb = Facing(rb, Eigen::Vector3f::UnitZ());
      }
      // One wall mask: the wall and the shelf's rear, as the 2D model drew.
      w.points_world.insert(w.points_world.end(), rs.points_world.begin(),
                            rs.points_world.end());
      w.points_world.insert(w.points_world.end(), rb.points_world.begin(),
                            rb.points_world.end());
      w.normals_world.insert(w.normals_world.end(), rs.normals_world.begin(),
                             rs.normals_world.end());
      w.normals_world.insert(w.normals_world.end(), rb.normals_world.begin(),
                             rb.normals_world.end());
      v.segments.push_back(std::move(w));
      v.segments.push_back(Segment(kFloor, 2, FloorPoints()));
      v.segments.push_back(Segment(kShelf, 3,
                                   Join({sides(rear_m + 0.02f, depth_m),
                                         shelves(rear_m + 0.02f, depth_m)})));
      out.push_back(std::move(v));
    }
    return out;
  };
  // Only what lies within the wall plane's tolerance (2.5 cm for a flat
  // wall, its voxels' centroids 1.5-3.5 cm out) is in question.
  auto near_wall = [](Cloud c) {
    std::erase_if(c, [](const Eigen::Vector3f& p) { return p.x() > 0.045f; });
    return c;
  };
  const Cloud rear_near =
      Join({near_wall(rear_sides), near_wall(rear_shelves)});
  ASSERT_GT(rear_near.size(), 100u);

  const SceneFusion fusion = Fuse(views(true));
  const SceneSegment* shelf = Largest(fusion, kShelf);
  const SceneSegment* wall_object = Largest(fusion, kWall);
  ASSERT_NE(shelf, nullptr);
  ASSERT_NE(wall_object, nullptr);
  EXPECT_EQ(Count(fusion, kShelf), 1u);
  EXPECT_GT(ShareIn(WhereItWent(fusion, rear_near), shelf->id), 0.8);
  EXPECT_GT(ShareIn(WhereItWent(fusion, wall), wall_object->id), 0.97);

  const SceneFusion old = Fuse(views(false));
  const SceneSegment* old_wall = Largest(old, kWall);
  ASSERT_NE(old_wall, nullptr);
  EXPECT_GT(ShareIn(WhereItWent(old, rear_near), old_wall->id), 0.8);
}

// The same shelf's back panel, 1 cm before the wall and turned like it, is
// called wall in every view (a 2D model sees a flat vertical surface between
// the boards); the shelf's sides and boards close it in on the wall's plane:
// it joins the shelf. The wall above the shelf stays wall, and so does the
// wall under a table against the wall (open below: nothing closes it in).
TEST(MapObjects, WallClosedInByAShelfOnTheWallJoinsIt) {
  const Cloud shelf = Join({Box({0.0f, 1.5f, 0.05f}, {0.36f, 1.5f, 1.8f}),
                            Box({0.0f, 2.4f, 0.05f}, {0.36f, 2.4f, 1.8f}),
                            Box({0.0f, 1.53f, 0.6f}, {0.36f, 2.37f, 0.6f}),
                            Box({0.0f, 1.53f, 1.2f}, {0.36f, 2.37f, 1.2f}),
                            Box({0.0f, 1.53f, 1.8f}, {0.36f, 2.37f, 1.8f})});
  const Cloud panel = Join({Box({0.01f, 1.53f, 0.65f}, {0.01f, 2.37f, 1.15f}),
                            Box({0.01f, 1.53f, 1.25f}, {0.01f, 2.37f, 1.75f})});
  // A table against the wall: its top and its legs touch it.
  const Cloud table = Join({Box({0.0f, 0.2f, 0.7f}, {0.6f, 1.2f, 0.74f}),
                            Box({0.0f, 0.2f, 0.05f}, {0.04f, 0.24f, 0.7f}),
                            Box({0.0f, 1.16f, 0.05f}, {0.04f, 1.2f, 0.7f})});
  Cloud wall = WallPoints();
  std::erase_if(wall, [](const Eigen::Vector3f& p) {
    return p.y() > 1.49f && p.y() < 2.41f && p.z() < 1.81f;
  });
  auto near = [](const Cloud& c, float y0, float y1, float z0, float z1) {
    Cloud out;
    for (const Eigen::Vector3f& p : c) {
      if (p.y() > y0 && p.y() < y1 && p.z() > z0 && p.z() < z1) {
        out.push_back(p);
      }
    }
    return out;
  };
  const Cloud above_shelf = near(wall, 1.6f, 2.3f, 1.95f, 2.4f);
  const Cloud under_table = near(wall, 0.3f, 1.1f, 0.1f, 0.6f);
  ASSERT_GT(above_shelf.size(), 20u);
  ASSERT_GT(under_table.size(), 100u);
  std::vector<View> views;
  for (int i = 0; i < 4; ++i) {
    View v;
    v.camera = {2.5f, 0.8f + 0.5f * static_cast<float>(i), 1.4f};
    v.segments.push_back(Segment(kWall, 1, Join({wall, panel})));
    v.segments.push_back(Segment(kFloor, 2, FloorPoints()));
    v.segments.push_back(Segment(kShelf, 3, shelf));
    v.segments.push_back(Segment(kTable, 4, table));
    views.push_back(std::move(v));
  }
  const SceneFusion fusion = Fuse(views);
  const SceneSegment* s = Largest(fusion, kShelf);
  const SceneSegment* w = Largest(fusion, kWall);
  ASSERT_NE(s, nullptr);
  ASSERT_NE(w, nullptr);
  EXPECT_GT(fusion.map_resolution()->enclosed_voxels_claimed, 50u);
  EXPECT_GT(ShareIn(WhereItWent(fusion, panel), s->id), 0.9);
  EXPECT_GT(ShareIn(WhereItWent(fusion, above_shelf), w->id), 0.9);
  EXPECT_GT(ShareIn(WhereItWent(fusion, under_table), w->id), 0.97);

  FusionOptions without;
  without.map_objects.claim_enclosed = false;
  const SceneFusion old = Fuse(views, without);
  const SceneSegment* old_wall = Largest(old, kWall);
  ASSERT_NE(old_wall, nullptr);
  EXPECT_GT(ShareIn(WhereItWent(old, panel), old_wall->id), 0.9);
}

}  // namespace
}  // namespace semrec::fuse
