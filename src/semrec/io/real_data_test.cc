// The readers against real public data ($SEMREC_DATA; skipped with a reason
// when absent).
#include <algorithm>
#include <cmath>
#include <unordered_map>

#include <gtest/gtest.h>

#include "semrec/io/sequence_reader.h"
#include "semrec/testing/test_util.h"

namespace fs = std::filesystem;

namespace semrec::io {
namespace {

std::vector<Eigen::Vector3d> BackProjectToWorld(const Frame& frame,
                                                const Transform& T_world_camera,
                                                int step) {
  std::vector<Eigen::Vector3d> points;
  for (int v = 0; v < frame.depth.height(); v += step) {
    for (int u = 0; u < frame.depth.width(); u += step) {
      const float z = frame.depth(u, v);
      if (z > 0.0f) {
        points.push_back(T_world_camera *
                         frame.intrinsics.BackProject(u, v, z));
      }
    }
  }
  return points;
}

// Median nearest-neighbour distance from `query` to `reference` (a hash grid,
// exact within `cell` m; farther neighbours count as `cell`).
double MedianNearestDistance(const std::vector<Eigen::Vector3d>& reference,
                             const std::vector<Eigen::Vector3d>& query,
                             double cell) {
  auto key = [cell](const Eigen::Vector3d& p, int dx, int dy, int dz) {
    const int64_t x = static_cast<int64_t>(std::floor(p.x() / cell)) + dx;
    const int64_t y = static_cast<int64_t>(std::floor(p.y() / cell)) + dy;
    const int64_t z = static_cast<int64_t>(std::floor(p.z() / cell)) + dz;
    return (x * 73856093) ^ (y * 19349663) ^ (z * 83492791);
  };
  std::unordered_map<int64_t, std::vector<const Eigen::Vector3d*>> grid;
  for (const auto& p : reference) grid[key(p, 0, 0, 0)].push_back(&p);
  std::vector<double> distances;
  for (const auto& q : query) {
    double best = cell;
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          auto it = grid.find(key(q, dx, dy, dz));
          if (it == grid.end()) continue;
          for (const auto* r : it->second) {
            best = std::min(best, (*r - q).norm());
          }
        }
      }
    }
    distances.push_back(best);
  }
  std::nth_element(distances.begin(), distances.begin() + distances.size() / 2,
                   distances.end());
  return distances[distances.size() / 2];
}

TEST(RealData, RedwoodLayout) {
  SEMREC_REQUIRE_SAMPLE_DATA(dir, "redwood_livingroom1_5");
  const SequenceReader reader = SequenceReader::Open(dir);
  EXPECT_EQ(reader.layout(), "redwood");
  EXPECT_EQ(reader.size(), 5u);
  EXPECT_EQ(reader.index().pose_source, "odometry.log");
  EXPECT_EQ(reader.intrinsics(),
            (CameraIntrinsics{640, 480, 525.0, 525.0, 319.5, 239.5}));
  const Frame f = reader.Read(0);
  EXPECT_EQ(f.color.width(), 640);
  EXPECT_TRUE(
      f.T_world_camera.translation().isApprox(Eigen::Vector3d(2, 2, -0.3)));
}

TEST(RealData, SevenScenesConsecutiveFramesOverlapInTheWorld) {
  SEMREC_REQUIRE_SAMPLE_DATA(dir, "7scenes_chess_0_99");
  const SequenceReader reader = SequenceReader::Open(dir);
  EXPECT_EQ(reader.layout(), "7scenes");
  ASSERT_EQ(reader.size(), 100u);
  EXPECT_DOUBLE_EQ(reader.intrinsics().fx, 585.0);
  const Frame f0 = reader.Read(0);
  const Frame f1 = reader.Read(1);
  const auto world0 = BackProjectToWorld(f0, f0.T_world_camera, 2);
  const auto world1 = BackProjectToWorld(f1, f1.T_world_camera, 8);
  ASSERT_GT(world0.size(), 10000u);
  const double median = MedianNearestDistance(world0, world1, 0.2);
  EXPECT_LT(median, 0.03)
      << "frames 0 and 1 should overlap within a few centimetres";
  // The wrong convention (poses read as world-to-camera) must be clearly worse,
  // or this test could not tell conventions apart. Frames 0 and 20 differ by
  // enough motion to show it.
  const Frame f20 = reader.Read(20);
  const auto right = BackProjectToWorld(f20, f20.T_world_camera, 8);
  const auto wrong = BackProjectToWorld(f20, f20.T_world_camera.Inverse(), 8);
  const auto wrong0 = BackProjectToWorld(f0, f0.T_world_camera.Inverse(), 2);
  const double median_right = MedianNearestDistance(world0, right, 0.2);
  const double median_wrong = MedianNearestDistance(wrong0, wrong, 0.2);
  EXPECT_LT(median_right, 0.03);
  EXPECT_GT(median_wrong, 2.0 * median_right);
}

TEST(RealData, ThreeDMatchSeqFolderWithParentIntrinsics) {
  SEMREC_REQUIRE_SAMPLE_DATA(dir, "3dmatch_5");
  const SequenceReader reader = SequenceReader::Open(dir);
  EXPECT_EQ(reader.layout(), "7scenes");
  EXPECT_EQ(reader.size(), 5u);
  EXPECT_NEAR(reader.intrinsics().fx, 570.342205, 1e-6);
  const Frame f = reader.Read(4);
  EXPECT_EQ(f.depth.width(), 640);
  size_t valid = 0;
  for (float d : f.depth.values()) valid += d > 0.0f;
  EXPECT_GT(valid, f.depth.NumPixels() / 2);
}

}  // namespace
}  // namespace semrec::io
