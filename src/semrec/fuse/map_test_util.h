// Helpers for the tests of objects decided per map voxel: surfaces of boxes,
// views of labelled segments, a fusion run over them and where a surface's
// points ended.
#pragma once

#include <algorithm>
#include <cstdint>
#include <initializer_list>
#include <map>
#include <vector>

#include <Eigen/Core>

#include "semrec/fuse/fusion.h"
#include "semrec/fuse/map_objects.h"

namespace semrec::fuse::map_test {

constexpr uint16_t kWall = 1, kFloor = 2, kChair = 3, kTable = 4, kSofa = 5,
                   kLamp = 6, kShelf = 7;

// Points on an axis-aligned box's surface (or a rectangle when one extent is
// zero), on a grid of `step_m`.
inline Cloud Box(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi,
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
// The points of `parts`, one after the other.
inline Cloud Join(std::initializer_list<Cloud> parts) {
  Cloud c;
  for (const Cloud& p : parts) c.insert(c.end(), p.begin(), p.end());
  return c;
}
inline Cloud WallPoints() { return Box({0, 0, 0.05f}, {0, 4, 2.5f}, 0.03f); }
inline Cloud FloorPoints() { return Box({0.05f, 0, 0}, {4, 4, 0}, 0.03f); }

inline FrameSegment Segment(uint16_t cls, uint16_t label, Cloud points) {
  FrameSegment s;
  s.class_id = cls;
  s.source_label = label;
  s.points_world = std::move(points);
  s.kind =
      cls == kWall || cls == kFloor ? ClassKind::kStuff : ClassKind::kThing;
  return s;
}

inline MapContext Context() {
  MapContext c;
  for (uint16_t id : {kWall, kFloor}) c.kinds[id] = ClassKind::kStuff;
  // Shelves have no known size (no max_length_m).
  for (uint16_t id : {kChair, kTable, kSofa, kLamp, kShelf}) {
    c.kinds[id] = ClassKind::kThing;
  }
  c.max_length_m[kChair] = 0.75;
  c.max_width_m[kChair] = 0.75;
  c.max_length_m[kSofa] = 3.0;
  c.max_width_m[kSofa] = 1.2;
  c.max_length_m[kTable] = 2.6;
  c.max_width_m[kTable] = 1.3;
  c.geometry[kWall] = StructureGeometry::kVertical;
  c.geometry[kFloor] = StructureGeometry::kFloor;
  return c;
}

struct View {
  std::vector<FrameSegment> segments;
  Cloud observed;  // besides the segments' own points
  Eigen::Vector3f camera{2.0f, 2.0f, 1.2f};
  FarView far;  // its labels where it had no depth (FarViewAlongMinusX)
};

// A Kinect's camera: 640 x 480, f 525 px (0.11 degrees a pixel).
inline CameraIntrinsics Kinect() {
  CameraIntrinsics k;
  k.width = 640;
  k.height = 480;
  k.fx = k.fy = 525.0;
  k.cx = 319.5;
  k.cy = 239.5;
  return k;
}

// A 640 x 480 camera (f 525 px) at `eye` looking along -x: image x = world
// +y, image y = world -z.
inline Transform LookingAlongMinusX(const Eigen::Vector3d& eye) {
  Eigen::Matrix3d R;
  R.col(0) = Eigen::Vector3d(0, 1, 0);
  R.col(1) = Eigen::Vector3d(0, 0, -1);
  R.col(2) = Eigen::Vector3d(-1, 0, 0);
  return Transform(R, eye);
}

// A view from `eye` along -x without any depth (it ranged up to `reach_m`
// elsewhere), every grid cell labelled class_of(pixel x, pixel y) (0: none).
template <typename ClassOf>
FarView FarViewAlongMinusX(const Eigen::Vector3d& eye, float reach_m,
                           const ClassOf& class_of) {
  FarView far;
  far.T_world_camera = LookingAlongMinusX(eye);
  far.intrinsics = Kinect();
  far.max_ranged_depth_m = reach_m;
  for (int row = 0; row < far.rows(); ++row) {
    for (int col = 0; col < far.columns(); ++col) {
      const uint16_t cls =
          class_of(col * FarView::kStride + FarView::kStride / 2,
                   row * FarView::kStride + FarView::kStride / 2);
      if (cls == 0) continue;
      far.cells.push_back(static_cast<uint32_t>(row * far.columns() + col));
      far.class_ids.push_back(cls);
      far.confidence.push_back(1.0f);
    }
  }
  return far;
}

// A view of the room's wall and floor, each one mask.
inline View RoomView() {
  View v;
  v.segments.push_back(Segment(kWall, 1, WallPoints()));
  v.segments.push_back(Segment(kFloor, 2, FloorPoints()));
  return v;
}

inline SceneFusion Fuse(const std::vector<View>& views,
                        FusionOptions options = {},
                        const MapContext& context = Context()) {
  options.merge = FusionOptions::Merge::kVoxel;
  SceneFusion fusion(options);
  for (size_t i = 0; i < views.size(); ++i) {
    FrameObservation observation;
    observation.camera_position_world = views[i].camera;
    observation.observed_world = views[i].observed;
    observation.far = views[i].far;
    for (const FrameSegment& s : views[i].segments) {
      observation.observed_world.insert(observation.observed_world.end(),
                                        s.points_world.begin(),
                                        s.points_world.end());
    }
    fusion.Integrate(views[i].segments, i, &observation);
  }
  fusion.Finish();
  fusion.ResolveMap(context);
  return fusion;
}

// Share of `points` lying within 3 cm of the segment's stored points, per
// object of the scene: where the ground-truth object's surface ended.
inline std::map<uint32_t, double> WhereItWent(const SceneFusion& fusion,
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

// The object holding the largest share of a surface (from WhereItWent).
inline uint32_t TopObject(const std::map<uint32_t, double>& went) {
  return std::max_element(
             went.begin(), went.end(),
             [](const auto& x, const auto& y) { return x.second < y.second; })
      ->first;
}

// `n` views, each showing the floor and `segments`.
inline std::vector<View> ViewsOf(int n,
                                 const std::vector<FrameSegment>& segments) {
  std::vector<View> views(static_cast<size_t>(n));
  for (View& v : views) {
    v.segments.push_back(Segment(kFloor, 1, FloorPoints()));
    v.segments.insert(v.segments.end(), segments.begin(), segments.end());
  }
  return views;
}

inline double ShareIn(const std::map<uint32_t, double>& went, uint32_t id) {
  const auto it = went.find(id);
  return it == went.end() ? 0.0 : it->second;
}

inline const SceneSegment* Largest(const SceneFusion& fusion, uint16_t cls) {
  const SceneSegment* best = nullptr;
  for (const SceneSegment& s : fusion.segments()) {
    if (s.class_id == cls && (!best || s.points.size() > best->points.size())) {
      best = &s;
    }
  }
  return best;
}

inline size_t Count(const SceneFusion& fusion, uint16_t cls) {
  return static_cast<size_t>(std::count_if(
      fusion.segments().begin(), fusion.segments().end(),
      [cls](const SceneSegment& s) { return s.class_id == cls; }));
}

}  // namespace semrec::fuse::map_test
