#include "semrec/synth/trajectory.h"

#include <cmath>
#include <map>
#include <string>

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/synth/generator.h"
#include "semrec/synth/render.h"

namespace semrec::synth {
namespace {

SynthOptions SparsePreset(const std::string& preset) {
  SynthOptions o = SynthOptions::Preset(preset);
  o.trajectory.kind = TrajectoryOptions::Kind::kSparse;
  o.scene.seed = o.seed;
  return o;
}

std::vector<Transform> Poses(const Scene& scene, const SynthOptions& o,
                             int frames) {
  return MakeTrajectory(scene, o.trajectory, frames, o.fps, o.seed);
}

// 1/8 of the presets' resolution, same field of view.
CameraIntrinsics Tiny(const SynthOptions& o) {
  return {o.width / 8,
          o.height / 8,
          o.fx / 8,
          o.fy / 8,
          (o.width / 8 - 1) / 2.0,
          (o.height / 8 - 1) / 2.0};
}

TEST(SparseViews, StayInTheRoomClearOfObjectsAndPeopleAtRobotHeight) {
  for (const std::string& preset : SynthOptions::PresetNames()) {
    const SynthOptions o = SparsePreset(preset);
    const TrajectoryOptions& t = o.trajectory;
    const Scene scene = GenerateScene(o.scene);
    const std::vector<Transform> poses = Poses(scene, o, 30);
    ASSERT_EQ(poses.size(), 30u);
    for (size_t i = 0; i < poses.size(); ++i) {
      SCOPED_TRACE(preset + " view " + std::to_string(i));
      const Eigen::Vector3d eye = poses[i].translation();
      const double c = t.sparse_clearance_m - 1e-9;
      EXPECT_GE(std::min(eye.x(), eye.y()), c);
      EXPECT_LE(eye.x(), scene.room_size.x() - c);
      EXPECT_LE(eye.y(), scene.room_size.y() - c);
      EXPECT_GE(eye.z(), t.sparse_min_height_m);
      EXPECT_LE(eye.z(), t.sparse_max_height_m);
      for (const SceneObject& object : scene.objects) {
        if (object.structure) continue;
        EXPECT_GE(object.Bounds().exteriorDistance(eye), c) << object.name;
      }
      for (const Person& person : scene.people) {
        const Eigen::Vector2d at = PoseAt(person, i / o.fps).position;
        EXPECT_GE((at - eye.head<2>()).norm(), c) << "person " << i;
      }
      // Forward-looking: at most max pitch down, never up, no roll.
      const Eigen::Vector3d forward = poses[i].rotation().col(2);
      EXPECT_LE(forward.z(), 1e-9);
      EXPECT_GE(forward.z(),
                -std::sin(t.sparse_max_pitch_deg * M_PI / 180.0) - 1e-9);
      EXPECT_NEAR(poses[i].rotation().col(0).z(), 0.0, 1e-9);
    }
  }
}

TEST(SparseViews, AreDeterministicPerFrameAndVaried) {
  const SynthOptions o = SparsePreset("office");
  const Scene scene = GenerateScene(o.scene);
  const std::vector<Transform> a = Poses(scene, o, 30), b = Poses(scene, o, 30);
  const std::vector<Transform> prefix = Poses(scene, o, 10);
  SynthOptions other = o;
  other.seed = 2;
  const std::vector<Transform> c = Poses(scene, other, 30);
  int far_apart = 0, same_as_other_seed = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].Matrix(), b[i].Matrix());
    if (i < prefix.size()) {
      EXPECT_EQ(a[i].Matrix(), prefix[i].Matrix());
    }
    same_as_other_seed += a[i].Matrix() == c[i].Matrix();
    if (i == 0) continue;
    // Consecutive views: a metre apart or turned by 45 degrees.
    const double moved = (a[i].translation() - a[i - 1].translation()).norm();
    const double turned =
        std::acos(
            std::clamp(a[i].rotation().col(2).dot(a[i - 1].rotation().col(2)),
                       -1.0, 1.0)) *
        180.0 / M_PI;
    far_apart += moved > 1.0 || turned > 45.0;
  }
  EXPECT_EQ(same_as_other_seed, 0);
  EXPECT_GE(far_apart, 24) << "of 29 consecutive pairs";
}

// The views look at something: median depth in range, objects in view.
TEST(SparseViews, LookAtObjectsFromAUsefulDistance) {
  for (const std::string preset : {"six-objects", "office"}) {
    const SynthOptions o = SparsePreset(preset);
    const Scene scene = GenerateScene(o.scene);
    const CameraIntrinsics k = Tiny(o);
    const std::vector<Transform> poses = Poses(scene, o, 20);
    int good = 0;
    for (size_t i = 0; i < poses.size(); ++i) {
      const RenderedFrame r = Render(scene, i / o.fps, poses[i], k);
      std::vector<float> depths = r.depth.values();
      std::nth_element(depths.begin(), depths.begin() + depths.size() / 2,
                       depths.end());
      const double median = depths[depths.size() / 2];
      size_t object_pixels = 0;
      for (size_t p = 0; p < r.instance.NumPixels(); ++p) {
        object_pixels += scene.IsObject(r.instance.data()[p]);
      }
      EXPECT_GT(median, 0.6) << preset << " view " << i;
      good += median <= o.trajectory.sparse_max_median_depth_m + 0.5 &&
              object_pixels >= r.instance.NumPixels() / 20;
    }
    EXPECT_GE(good, 18) << preset << ": of 20 views";
  }
}

// Like a house walk-through: many objects are seen in one or two views only
// (30 views of the office; each sees 1-4 objects within the sensor's 4 m).
TEST(SparseViews, SeeManyObjectsInOneOrTwoViews) {
  const SynthOptions o = SparsePreset("office");
  const Scene scene = GenerateScene(o.scene);
  const CameraIntrinsics k = Tiny(o);
  const std::vector<Transform> poses = Poses(scene, o, 30);
  std::map<uint16_t, int> views;  // object -> views with >= 10 pixels
  for (size_t i = 0; i < poses.size(); ++i) {
    const RenderedFrame r = Render(scene, i / o.fps, poses[i], k);
    std::map<uint16_t, int> pixels;
    for (size_t p = 0; p < r.instance.NumPixels(); ++p) {
      if (r.depth.data()[p] <= 4.0f) ++pixels[r.instance.data()[p]];
    }
    for (const auto& [id, n] : pixels) {
      if (scene.IsObject(id) && n >= 10) ++views[id];
    }
  }
  int rare = 0;
  for (const auto& [id, n] : views) rare += n <= 2;
  EXPECT_GE(views.size(), 18u) << "most of the 24 objects are seen";
  EXPECT_GE(rare * 4, static_cast<int>(views.size()))
      << rare << " of " << views.size() << " seen objects in <= 2 views";
}

TEST(SparseViews, BadOptionsGiveClearErrors) {
  TrajectoryOptions t;
  t.sparse_min_height_m = 1.5;
  t.sparse_max_height_m = 1.0;
  EXPECT_THROW(t.Check(), InvalidArgument);
  t = TrajectoryOptions();
  t.sparse_clearance_m = -0.1;
  EXPECT_THROW(t.Check(), InvalidArgument);
  t = TrajectoryOptions();
  t.sparse_min_median_depth_m = 5.0;
  EXPECT_THROW(t.Check(), InvalidArgument);
  SynthOptions o = SparsePreset("six-objects");
  o.trajectory.sparse_max_height_m = 2.6;
  EXPECT_THROW(o.Check(), InvalidArgument);
}

}  // namespace
}  // namespace semrec::synth
