#include "semrec/synth/render.h"

#include <cmath>
#include <map>

#include <gtest/gtest.h>

namespace semrec::synth {
namespace {

const CameraIntrinsics kK{160, 120, 131.25, 131.25, 79.5, 59.5};

Scene EmptyRoom() {
  SceneOptions options;
  options.object_classes = {};
  return GenerateScene(options);
}

// Camera 1.3 m above the floor, pitched down: every floor pixel's depth equals
// the analytic ray-plane intersection.
TEST(Render, FloorDepthIsAnalytic) {
  const Scene scene = EmptyRoom();
  const Eigen::Matrix3d R_down =
      (Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitZ()) *
       Eigen::AngleAxisd(-M_PI / 2 - 0.6, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  const Transform T_world_camera(R_down, Eigen::Vector3d(2.5, 2.0, 1.3));
  const RenderedFrame r = Render(scene, 0.0, T_world_camera, kK);
  size_t floor_pixels = 0;
  for (int v = 0; v < kK.height; ++v) {
    for (int u = 0; u < kK.width; ++u) {
      if (r.semantic(u, v) != kClassFloor) continue;
      ++floor_pixels;
      const Eigen::Vector3d dir =
          R_down * Eigen::Vector3d((u - kK.cx) / kK.fx, (v - kK.cy) / kK.fy, 1);
      const double z =
          -1.3 / dir.z();  // camera-frame z of the floor point (dir has unit z)
      ASSERT_NEAR(r.depth(u, v), z, 1e-6 * z) << u << "," << v;
    }
  }
  EXPECT_GT(floor_pixels, static_cast<size_t>(kK.width * kK.height) / 4);
}

// Looking straight at a wall: constant depth equal to the distance.
TEST(Render, FrontoParallelWall) {
  const Scene scene = EmptyRoom();
  // Camera z along world +x, at x = 1.0: the wall at x = 5 is 4 m away.
  Eigen::Matrix3d R;
  R.col(0) = Eigen::Vector3d(0, -1, 0);
  R.col(1) = Eigen::Vector3d(0, 0, -1);
  R.col(2) = Eigen::Vector3d(1, 0, 0);
  const RenderedFrame r = Render(scene, 0.0, Transform(R, {1.0, 2.0, 1.3}), kK);
  EXPECT_EQ(r.semantic(80, 60), kClassWall);
  EXPECT_FLOAT_EQ(r.depth(80, 60), 4.0f);
  EXPECT_FLOAT_EQ(r.depth(70, 50), 4.0f);
  // The ray through pixel (80, 60) is half a pixel off the optical axis in u
  // and v.
  const double off = 0.5 / kK.fx;
  EXPECT_NEAR(r.cos_incidence(80, 60), 1.0 / std::sqrt(1.0 + 2 * off * off),
              1e-6);
}

TEST(Render, BackProjectedPixelsLieOnTheirObject) {
  SceneOptions options;
  options.num_people = 2;
  const Scene scene = GenerateScene(options);
  const Transform T_world_camera = LookAt({2.5, 0.3, 1.8}, {2.5, 3.0, 0.5});
  const RenderedFrame r = Render(scene, 0.5, T_world_camera, kK);
  std::map<uint16_t, uint16_t> class_of_instance;
  size_t checked = 0;
  for (int v = 0; v < kK.height; ++v) {
    for (int u = 0; u < kK.width; ++u) {
      const uint16_t id = r.instance(u, v);
      ASSERT_NE(id, 0);  // a closed room: every ray hits something
      auto [it, inserted] = class_of_instance.emplace(id, r.semantic(u, v));
      ASSERT_EQ(it->second, r.semantic(u, v))
          << "instance " << id << " has two classes";
      ASSERT_EQ(r.person(u, v) != 0, id >= kPersonInstanceBase);
      const SceneObject* object = scene.FindObject(id);
      if (object == nullptr) {
        continue;  // people move; checked through the person map above
      }
      ASSERT_EQ(object->class_id, r.semantic(u, v));
      const Eigen::Vector3d p =
          T_world_camera * kK.BackProject(u, v, r.depth(u, v));
      ASSERT_LT(object->DistanceToSurface(p), 1e-5) << object->name;
      ++checked;
    }
  }
  EXPECT_GT(checked, static_cast<size_t>(kK.width * kK.height) / 2);
  EXPECT_GT(class_of_instance.size(), 4u);
}

}  // namespace
}  // namespace semrec::synth
