#include "semrec/fuse/map_projection.h"

#include <cmath>
#include <map>
#include <set>

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/fuse/map_test_util.h"

namespace semrec::fuse {
namespace {

// A fronto-parallel rectangle [x0, x1] x [y0, y1] at depth z (camera frame).
struct Plate {
  uint32_t id;
  uint16_t class_id;
  float x0, x1, y0, y1, z;
  bool Hit(float x, float y) const {
    return x >= x0 && x <= x1 && y >= y0 && y <= y1;
  }
};

CameraIntrinsics Camera() {
  CameraIntrinsics k;
  k.width = 160;
  k.height = 120;
  k.fx = k.fy = 100;
  k.cx = 80;
  k.cy = 60;
  return k;
}

// The map's object: the plate as the fusion stores it (centres of its 5 cm
// voxels), moved into the world by T_world_camera.
SceneSegment Object(const Plate& p, const Transform& T_world_camera,
                    float spacing_m = 0.05f) {
  SceneSegment s;
  s.id = p.id;
  s.class_id = p.class_id;
  const int nx = static_cast<int>(std::lround((p.x1 - p.x0) / spacing_m));
  const int ny = static_cast<int>(std::lround((p.y1 - p.y0) / spacing_m));
  for (int i = 0; i < nx; ++i) {
    for (int j = 0; j < ny; ++j) {
      const Eigen::Vector3d p_camera(p.x0 + spacing_m * (i + 0.5),
                                     p.y0 + spacing_m * (j + 0.5), p.z);
      s.points.push_back((T_world_camera * p_camera).cast<float>());
    }
  }
  return s;
}

// Measured depth: the nearest plate along each pixel's ray, else a wall at 4 m;
// and the id of the plate seen (ground truth).
DepthImage Render(const std::vector<Plate>& plates, Image<uint32_t>* gt_ids) {
  const CameraIntrinsics k = Camera();
  DepthImage depth(k.width, k.height, 1, 4.0f);
  *gt_ids = Image<uint32_t>(k.width, k.height);
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      for (const Plate& p : plates) {
        const float x = static_cast<float>((u - k.cx) * p.z / k.fx);
        const float y = static_cast<float>((v - k.cy) * p.z / k.fy);
        if (p.Hit(x, y) && p.z < depth(u, v)) {
          depth(u, v) = p.z;
          (*gt_ids)(u, v) = p.id;
        }
      }
    }
  }
  return depth;
}

double Iou(const Image<uint32_t>& a, const Image<uint32_t>& b, uint32_t id) {
  size_t inter = 0, uni = 0;
  for (size_t i = 0; i < a.values().size(); ++i) {
    const bool in_a = a.values()[i] == id;
    const bool in_b = b.values()[i] == id;
    inter += in_a && in_b;
    uni += in_a || in_b;
  }
  return uni ? static_cast<double>(inter) / static_cast<double>(uni) : 0.0;
}

const Plate kTablePlate{5, 3, -0.5f, 0.0f, -0.25f, 0.25f, 2.0f};
const Plate kChairPlate{7, 4, 0.2f, 0.6f, -0.2f, 0.2f, 2.5f};

TEST(MapProjection, ExplainsKnownObjectsWithTheirIdsAndClasses) {
  for (const Transform& T_world_camera :
       {Transform(),
        Transform::FromQuaternion(Eigen::Quaterniond(0.9, 0.1, -0.3, 0.2),
                                  Eigen::Vector3d(1.0, -2.0, 0.5))}) {
    Image<uint32_t> gt;
    const DepthImage depth = Render({kTablePlate, kChairPlate}, &gt);
    const ProjectedMap map = ProjectMap({Object(kTablePlate, T_world_camera),
                                         Object(kChairPlate, T_world_camera)},
                                        Camera(), T_world_camera, depth);
    EXPECT_GT(Iou(map.object_id, gt, 5), 0.85);
    EXPECT_GT(Iou(map.object_id, gt, 7), 0.85);
    size_t gt_pixels = 0, explained_on_gt = 0, explained_off_gt = 0;
    for (int v = 0; v < depth.height(); ++v) {
      for (int u = 0; u < depth.width(); ++u) {
        const bool explained = map.state(u, v) == ProjectedMap::kExplained;
        if (gt(u, v) != 0) {
          ++gt_pixels;
          explained_on_gt += explained;
          if (map.object_id(u, v) == gt(u, v)) {
            EXPECT_EQ(map.class_id(u, v), gt(u, v) == 5 ? 3 : 4);
            EXPECT_NEAR(map.depth_m(u, v), depth(u, v), 0.01);
          }
        } else {
          explained_off_gt += explained;
        }
      }
    }
    // The objects are explained; the wall behind them (not in the map) is not.
    EXPECT_GT(explained_on_gt, 0.95 * static_cast<double>(gt_pixels));
    EXPECT_LT(explained_off_gt, 0.02 * static_cast<double>(depth.NumPixels()));
    EXPECT_EQ(map.valid_depth_pixels, depth.NumPixels());
    EXPECT_NEAR(map.UnexplainedShare(),
                1.0 - static_cast<double>(gt_pixels) /
                          static_cast<double>(depth.NumPixels()),
                0.03);
    EXPECT_EQ(map.contradicted_pixels, 0u);
  }
}

TEST(MapProjection, ANewObjectInFrontIsUnexplainedAndARemovedOneContradicts) {
  // A box enters in front of part of the table: those pixels are new, not the
  // table.
  const Plate box{9, 6, -0.3f, 0.1f, 0.0f, 0.3f, 1.5f};
  Image<uint32_t> gt;
  const DepthImage depth = Render({kTablePlate, kChairPlate, box}, &gt);
  const ProjectedMap map = ProjectMap(
      {Object(kTablePlate, {}), Object(kChairPlate, {})}, Camera(), {}, depth);
  size_t box_pixels = 0, box_explained = 0, box_contradicted = 0;
  for (size_t i = 0; i < gt.values().size(); ++i) {
    if (gt.values()[i] != 9) continue;
    ++box_pixels;
    box_explained += map.state.values()[i] == ProjectedMap::kExplained;
    box_contradicted += map.state.values()[i] == ProjectedMap::kContradicted;
  }
  ASSERT_GT(box_pixels, 500u);
  EXPECT_EQ(box_explained, 0u);
  EXPECT_EQ(box_contradicted,
            0u);  // something in front of the map is new, not a contradiction

  // The chair was taken away: the camera sees the wall where the map has the
  // chair.
  const DepthImage without_chair = Render({kTablePlate}, &gt);
  const ProjectedMap after =
      ProjectMap({Object(kTablePlate, {}), Object(kChairPlate, {})}, Camera(),
                 {}, without_chair);
  size_t chair_pixels = 0, chair_explained = 0, chair_contradicted = 0;
  for (size_t i = 0; i < gt.values().size(); ++i) {
    if (after.object_id.values()[i] != 7) continue;
    ++chair_pixels;
    chair_explained += after.state.values()[i] == ProjectedMap::kExplained;
    chair_contradicted +=
        after.state.values()[i] == ProjectedMap::kContradicted;
  }
  ASSERT_GT(chair_pixels, 200u);
  EXPECT_EQ(chair_explained, 0u);
  // All of it but the one-pixel rim of its silhouette, and nothing else.
  EXPECT_GT(chair_contradicted, 0.7 * static_cast<double>(chair_pixels))
      << chair_pixels;
  EXPECT_EQ(after.contradicted_pixels, chair_contradicted);
}

TEST(MapProjection, OneSurfaceFusedTwiceDoesNotSpeckle) {
  // A wall fused once as "wall" (dense, 4 mm behind the measured surface) and
  // in places as "cabinet" (sparse, on the surface): to the camera one
  // surface. Each cabinet splat explains its pixels a little better, but the
  // wall explains most of every neighbourhood: the wall gets them all. A book
  // 4 cm in front of the wall is no such tie: it keeps its pixels.
  const Plate wall{1, 1, -0.6f, 0.6f, -0.4f, 0.4f, 2.004f};
  const Plate cabinet{2, 11, -0.6f, 0.0f, -0.4f, 0.4f, 2.0f};
  const Plate book{3, 67, 0.2f, 0.4f, -0.1f, 0.1f, 1.96f};
  const Plate measured{1, 1, -0.6f, 0.6f, -0.4f, 0.4f, 2.0f};
  Image<uint32_t> gt;
  const DepthImage depth = Render({measured, book}, &gt);
  const std::vector<SceneSegment> map = {
      Object(wall, {}), Object(cabinet, {}, 0.1f), Object(book, {})};
  size_t cabinet_px = 0, covered = 0;
  for (const float ratio : {0.0f, 0.2f}) {
    MapProjectionOptions options;
    options.ambiguity_ratio = ratio;
    const ProjectedMap p = ProjectMap(map, Camera(), {}, depth, options);
    cabinet_px = covered = 0;
    for (int v = 43; v < 77; ++v) {    // inside the wall plate
      for (int u = 53; u < 77; ++u) {  // ... where the cabinet lies too
        ASSERT_EQ(p.state(u, v), ProjectedMap::kExplained) << u << "," << v;
        ++covered;
        cabinet_px += p.object_id(u, v) == 2 ? 1 : 0;
      }
    }
    if (ratio == 0.0f) {
      // Without the rule: speckle, a third of the pixels go to the cabinet.
      EXPECT_GT(cabinet_px, covered / 5);
    } else {
      EXPECT_LT(cabinet_px, covered / 50);
    }
    // The book's interior (x 0.2..0.4 m, y -0.1..0.1 m at 1.96 m) is the book.
    for (int v = 57; v < 63; ++v) {
      for (int u = 92; u < 99; ++u) EXPECT_EQ(p.object_id(u, v), 3u);
    }
  }
}

TEST(MapProjection, TheDecidedMapGivesAFrontOneClassAndEachVoxelOnce) {
  // A shelf against the wall that two of four views called wall (their wall
  // mask holds it): the fusion keeps it in the wall object and in a shelf
  // object, and projected those interleave; the decided map (the wall vote is
  // off the wall's plane) holds each voxel once, as shelf, under an id the
  // fusion knows.
  using namespace map_test;  // NOLINT(google-build-using-namespace)
  const Cloud shelf = Box({0.05f, 1.0f, 0.0f}, {0.35f, 2.0f, 0.8f});
  FusionOptions options;
  options.merge = FusionOptions::Merge::kVoxel;
  SceneFusion fusion(options);
  const Eigen::Vector3d eye(2.5, 1.5, 0.6);
  for (size_t i = 0; i < 4; ++i) {
    std::vector<FrameSegment> segments;
    if (i % 2 == 0) {
      segments.push_back(Segment(kWall, 1, Join({WallPoints(), shelf})));
    } else {
      segments.push_back(Segment(kWall, 1, WallPoints()));
      segments.push_back(Segment(kShelf, 2, shelf));
    }
    segments.push_back(Segment(kFloor, 3, FloorPoints()));
    FrameObservation observation;
    observation.camera_position_world = eye.cast<float>();
    for (const FrameSegment& s : segments) {
      observation.observed_world.insert(observation.observed_world.end(),
                                        s.points_world.begin(),
                                        s.points_world.end());
    }
    fusion.Integrate(segments, i, &observation);
  }
  const MapResolution resolution = fusion.PreviewResolution(Context());
  const VoxelEvidenceMap& evidence = *fusion.voxel_evidence();
  const std::vector<SceneSegment> decided =
      DecidedMapForProjection(fusion.segments(), resolution, evidence);

  // Each decided voxel once; every id one the fusion has.
  std::set<uint32_t> fusion_ids;
  for (const SceneSegment& s : fusion.segments()) fusion_ids.insert(s.id);
  std::map<uint64_t, int> seen;
  for (const SceneSegment& s : decided) {
    EXPECT_EQ(fusion_ids.count(s.id), 1u) << s.id;
    for (const Eigen::Vector3f& p : s.points) {
      const uint64_t key = VoxelKey(p, evidence.inv_voxel_size());
      if (resolution.owners.count(key) != 0) ++seen[key];
    }
  }
  ASSERT_EQ(seen.size(), resolution.owners.size());
  for (const auto& [key, n] : seen) ASSERT_EQ(n, 1) << key;
  // Stored points in no decided voxel stay, with their object's id and class.
  std::vector<SceneSegment> with_stray = fusion.segments();
  with_stray.push_back({});
  with_stray.back().id = 99;
  with_stray.back().class_id = kLamp;
  with_stray.back().points = {Eigen::Vector3f(3.0f, 3.0f, 1.0f)};
  const std::vector<SceneSegment> stray =
      DecidedMapForProjection(with_stray, resolution, evidence);
  ASSERT_EQ(stray.size(), decided.size() + 1);
  EXPECT_EQ(stray.back().id, 99u);
  EXPECT_EQ(stray.back().class_id, kLamp);

  // Seen from the room: the shelf's front face (x = 0.35 m) in front of the
  // wall (x = 0).
  const CameraIntrinsics k = Kinect();
  const Transform T_world_camera = LookingAlongMinusX(eye);
  DepthImage depth(k.width, k.height);
  Image<uint8_t> on_front(k.width, k.height);
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const Eigen::Vector3d ray =
          T_world_camera.rotation() *
          Eigen::Vector3d((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
      const double t_front = (0.35 - eye.x()) / ray.x();
      const Eigen::Vector3d hit = eye + t_front * ray;
      // Well inside the front (its rim is shared with the top and sides).
      const bool front =
          hit.y() > 1.1 && hit.y() < 1.9 && hit.z() > 0.1 && hit.z() < 0.7;
      const double t = front ? t_front : -eye.x() / ray.x();
      depth(u, v) = static_cast<float>(t);  // along the optical axis: z = t
      on_front(u, v) = front ? 1 : 0;
    }
  }
  const auto shelf_share = [&](const std::vector<SceneSegment>& map) {
    const ProjectedMap p = ProjectMap(map, k, T_world_camera, depth);
    size_t front_px = 0, shelf_px = 0;
    for (size_t i = 0; i < on_front.values().size(); ++i) {
      if (on_front.values()[i] == 0) continue;
      ++front_px;
      shelf_px += p.class_id.values()[i] == kShelf ? 1 : 0;
    }
    return static_cast<double>(shelf_px) / static_cast<double>(front_px);
  };
  std::vector<SceneSegment> raw;
  for (const SceneSegment& s : fusion.segments()) {
    raw.push_back({});
    raw.back().id = s.id;
    raw.back().class_id = s.class_id;
    raw.back().points = s.points;
  }
  const double raw_share = shelf_share(raw);
  const double decided_share = shelf_share(decided);
  EXPECT_GT(decided_share, 0.99) << "raw " << raw_share;
  EXPECT_LT(raw_share, 0.9) << "decided " << decided_share;  // before
}

TEST(MapProjection, NearerObjectsHideFartherOnesAndBadInputIsRefused) {
  // The chair moved behind the table's plane: where both project, the nearer
  // (table) wins.
  const Plate behind{7, 4, -0.4f, 0.0f, -0.2f, 0.2f, 3.0f};
  Image<uint32_t> gt;
  const DepthImage depth = Render({kTablePlate, behind}, &gt);
  const ProjectedMap map = ProjectMap(
      {Object(behind, {}), Object(kTablePlate, {})}, Camera(), {}, depth);
  EXPECT_EQ(map.object_id(70, 60), 5u);  // this ray passes through both plates
  EXPECT_NEAR(map.depth_m(70, 60), 2.0, 1e-5);
  EXPECT_EQ(map.state(70, 60), ProjectedMap::kExplained);

  // Behind the camera or without depth: nothing projects, nothing is valid.
  const ProjectedMap empty = ProjectMap(
      {Object(kTablePlate,
              Transform::FromQuaternion(Eigen::Quaterniond(0, 1, 0, 0),
                                        Eigen::Vector3d::Zero()))},
      Camera(), {}, DepthImage(160, 120));
  EXPECT_EQ(empty.valid_depth_pixels, 0u);
  EXPECT_DOUBLE_EQ(empty.UnexplainedShare(), 1.0);
  for (uint8_t state : empty.state.values()) {
    ASSERT_EQ(state, ProjectedMap::kNoDepth);
  }
  for (uint32_t id : empty.object_id.values()) ASSERT_EQ(id, 0u);

  EXPECT_THROW(ProjectMap({}, Camera(), {}, DepthImage(10, 10)),
               InvalidArgument);
  MapProjectionOptions bad;
  bad.splat_radius_m = 0;
  EXPECT_THROW(bad.Check(), InvalidArgument);
  bad = {};
  bad.depth_tolerance_ratio = -1;
  EXPECT_THROW(bad.Check(), InvalidArgument);
  bad = {};
  bad.ambiguity_ratio = 2;
  EXPECT_THROW(bad.Check(), InvalidArgument);
}

}  // namespace
}  // namespace semrec::fuse
