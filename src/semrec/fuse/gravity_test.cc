#include "semrec/fuse/gravity.h"

#include <gtest/gtest.h>

#include <cmath>

#include "semrec/core/error.h"
#include "semrec/core/random.h"

namespace semrec::fuse {
namespace {

// Calls f(a, b) at a0 + i * sa (< a1), b0 + j * sb (< b1): integer counters,
// so every grid has the same points whatever the float rounding.
template <typename F>
void ForGrid(float a0, float a1, float sa, float b0, float b1, float sb, F f) {
  const int na = static_cast<int>(std::ceil((a1 - a0) / sa - 1e-4f));
  const int nb = static_cast<int>(std::ceil((b1 - b0) / sb - 1e-4f));
  for (int i = 0; i < na; ++i) {
    for (int j = 0; j < nb; ++j) f(a0 + i * sa, b0 + j * sb);
  }
}

// A Z-up room with the floor at z = 0: floor, a table top at 0.75 m (larger
// than a seat, smaller than the floor), a seat at 0.45 m, one wall and noise.
struct Room {
  Cloud floor, table, seat, wall;
  std::vector<Transform> cameras;
};

Room MakeRoom(uint64_t seed) {
  Rng rng(seed);
  Room r;
  const auto noise = [&] { return static_cast<float>(rng.Normal() * 0.005); };
  ForGrid(0, 4, 0.05f, 0, 4, 0.05f,
          [&](float x, float y) { r.floor.emplace_back(x, y, noise()); });
  ForGrid(1, 2.2f, 0.05f, 1, 2, 0.05f, [&](float x, float y) {
    r.table.emplace_back(x, y, 0.75f + noise());
  });
  ForGrid(3, 3.5f, 0.05f, 1, 1.5f, 0.05f, [&](float x, float y) {
    r.seat.emplace_back(x, y, 0.45f + noise());
  });
  ForGrid(0, 4, 0.05f, 0, 2.5f, 0.05f,
          [&](float y, float z) { r.wall.emplace_back(noise(), y, z); });
  // Hand-held cameras at eye height, looking around with a few degrees of
  // roll and pitch.
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector3d eye(2 + rng.Uniform(-0.5, 0.5),
                              3 + rng.Uniform(-0.5, 0.5), 1.5);
    const Eigen::Vector3d target(rng.Uniform(0, 4), rng.Uniform(0, 2),
                                 rng.Uniform(0.2, 1.2));
    const Eigen::Vector3d up =
        (Eigen::Vector3d::UnitZ() +
         Eigen::Vector3d(rng.Uniform(-0.1, 0.1), rng.Uniform(-0.1, 0.1), 0))
            .normalized();
    r.cameras.push_back(LookAt(eye, target, up));
  }
  return r;
}

Cloud Apply(const Transform& T, const Cloud& c) {
  Cloud out;
  for (const auto& p : c) out.push_back((T * p.cast<double>()).cast<float>());
  return out;
}

TEST(Gravity, RecoversUpAndFloorOfATiltedRoom) {
  const Room room = MakeRoom(3);
  // 7-Scenes-like world: y down, tilted, floor far from the origin.
  const Transform T_world_true(
      Eigen::AngleAxisd(1.9, Eigen::Vector3d(1, 0.2, 0.1).normalized())
          .toRotationMatrix(),
      Eigen::Vector3d(0.3, -1.2, 2.0));
  const Cloud floor = Apply(T_world_true, room.floor),
              table = Apply(T_world_true, room.table),
              seat = Apply(T_world_true, room.seat),
              wall = Apply(T_world_true, room.wall);
  std::vector<Transform> cameras;
  for (const Transform& T : room.cameras) cameras.push_back(T_world_true * T);

  for (bool with_floor_class : {false, true}) {
    SCOPED_TRACE(with_floor_class ? "floor class" : "planes");
    const std::vector<bool> is_floor = {false, false, with_floor_class, false};
    const GravityEstimate e =
        EstimateGravity({&table, &seat, &floor, &wall}, is_floor, cameras, {});
    EXPECT_EQ(e.method, with_floor_class ? "floor class" : "planes");
    // Composed with the true world transform, the estimate must give back the
    // room's own frame up to a spin about Z.
    const Transform T = e.T_upright_world * T_world_true;
    EXPECT_GT((T.rotation() * Eigen::Vector3d::UnitZ()).z(),
              std::cos(0.5 * M_PI / 180));
    for (const auto& p : room.floor) {
      ASSERT_NEAR((T * p.cast<double>()).z(), 0.0, 0.03);
    }
    for (const auto& p : room.table) {
      ASSERT_NEAR((T * p.cast<double>()).z(), 0.75, 0.03);
    }
    EXPECT_GT(e.floor_points, room.floor.size() / 2);
  }
}

TEST(Gravity, TheFloorIsTheLowestLargePlaneNotTheLargest) {
  // A big table top above a smaller visible patch of floor.
  Room room = MakeRoom(4);
  Cloud floor_patch, big_table;
  for (const auto& p : room.floor) {
    if (p.x() < 2.0f && p.y() < 2.0f) floor_patch.push_back(p);  // a third
  }
  ForGrid(0, 3.5f, 0.05f, 0, 3.5f, 0.05f,
          [&](float x, float y) { big_table.emplace_back(x, y, 0.75f); });
  const GravityEstimate e =
      EstimateGravity({&big_table, &floor_patch}, {}, room.cameras, {});
  EXPECT_EQ(e.method, "already upright");
  EXPECT_TRUE(e.T_upright_world.IsApprox(Transform()));
  // Lifted by 1 m: the floor comes back to 0, not the table.
  const Transform lift(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 1));
  const Cloud t2 = Apply(lift, big_table), f2 = Apply(lift, floor_patch);
  std::vector<Transform> cams;
  for (const auto& T : room.cameras) cams.push_back(lift * T);
  const GravityEstimate lifted = EstimateGravity({&t2, &f2}, {}, cams, {});
  EXPECT_EQ(lifted.method, "planes");
  EXPECT_NEAR(lifted.floor_height_m, 1.0, 0.01);
  EXPECT_NEAR(lifted.T_upright_world.translation().z(), -1.0, 0.01);
}

TEST(Gravity, CamerasLookingSteeplyDownDoNotTurnAWallIntoTheFloor) {
  // The six-objects orbit: 8 frames turning 16 degrees, looking down by 48.
  // The cameras' image-up is then 48 degrees from up and only 42 from the
  // back wall's normal; the cameras look up at that wall, down at the floor.
  Room room = MakeRoom(7);
  Cloud back_wall;  // y = 0, behind the cameras, larger than the floor seen
  ForGrid(0, 4, 0.05f, 0, 3.0f, 0.04f,
          [&](float x, float z) { back_wall.emplace_back(x, 0, z); });
  Cloud floor_seen;
  for (const auto& p : room.floor) {
    if (p.y() > 1.5f && p.y() < 3.5f) floor_seen.push_back(p);
  }
  std::vector<Transform> cameras;
  for (int i = 0; i < 8; ++i) {
    const double yaw = (i - 4) * 2.0 * M_PI / 180;
    const Eigen::Vector3d eye(2, 0.5, 2.1);
    const Eigen::Vector3d dir(std::sin(yaw) * std::cos(0.84),
                              std::cos(yaw) * std::cos(0.84), -std::sin(0.84));
    cameras.push_back(LookAt(eye, eye + dir));
  }
  const GravityEstimate e =
      EstimateGravity({&floor_seen, &back_wall, &room.table}, {}, cameras, {});
  EXPECT_EQ(e.method, "already upright");
  EXPECT_GT(e.up_world.z(), 0.999);
  // Without the look-up rule the back wall would be the floor.
  GravityOptions no_rule;
  no_rule.max_look_up_deg = 89;
  const GravityEstimate wrong = EstimateGravity(
      {&floor_seen, &back_wall, &room.table}, {}, cameras, no_rule);
  EXPECT_LT(wrong.up_world.z(), 0.9);
}

TEST(Gravity, UprightWorldsAreKeptExactlyAndNoneDoesNothing) {
  const Room room = MakeRoom(5);
  const GravityEstimate e = EstimateGravity(
      {&room.floor, &room.table, &room.wall}, {}, room.cameras, {});
  EXPECT_EQ(e.method, "already upright");
  EXPECT_EQ(e.T_upright_world.Matrix(), Eigen::Matrix4d::Identity());

  const Transform tilted(
      Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitX()).toRotationMatrix(),
      Eigen::Vector3d::Zero());
  const Cloud f = Apply(tilted, room.floor);
  const GravityEstimate none =
      EstimateGravity({&f}, {}, room.cameras, ParseGravity("none"));
  EXPECT_EQ(none.method, "none");
  EXPECT_EQ(none.T_upright_world.Matrix(), Eigen::Matrix4d::Identity());
}

TEST(Gravity, GivenUpIsUsedAndParsed) {
  const GravityOptions o = ParseGravity("0,-2,0");
  EXPECT_EQ(o.mode, GravityOptions::Mode::kGiven);
  EXPECT_TRUE(o.up.isApprox(Eigen::Vector3d(0, -1, 0)));
  EXPECT_EQ(ParseGravity("auto").mode, GravityOptions::Mode::kAuto);
  for (const char* bad :
       {"", "up", "0,0", "0,0,0", "1,2,3,4", "0;0;1", "nan,0,1"}) {
    EXPECT_THROW(ParseGravity(bad), InvalidArgument) << bad;
  }
  // A y-down world: up = -y.
  const Room room = MakeRoom(6);
  const Transform T_world_true(
      Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix(),
      Eigen::Vector3d(0, 0.5, 0));
  const Cloud floor = Apply(T_world_true, room.floor);
  const GravityEstimate e =
      EstimateGravity({&floor}, {}, {Transform()}, ParseGravity("0,-1,0"));
  EXPECT_EQ(e.method, "given");
  for (const auto& p : room.floor) {
    ASSERT_NEAR((e.T_upright_world * T_world_true * p.cast<double>()).z(), 0.0,
                0.02);
  }
}

}  // namespace
}  // namespace semrec::fuse
