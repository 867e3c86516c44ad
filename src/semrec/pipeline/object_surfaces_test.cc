#include "semrec/pipeline/object_surfaces.h"

#include <gtest/gtest.h>

#include "semrec/fuse/voxel.h"

namespace semrec::pipeline {
namespace {

// A flat grid of triangles in the plane x = `x`, y and z in [0, size).
std::shared_ptr<open3d::geometry::TriangleMesh> Sheet(double x, double y0,
                                                      double size,
                                                      double step = 0.02) {
  auto mesh = std::make_shared<open3d::geometry::TriangleMesh>();
  const int n = static_cast<int>(size / step);
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) {
      mesh->vertices_.emplace_back(x, y0 + i * step, j * step);
      mesh->vertex_colors_.emplace_back(0.5, 0.5, 0.5);
    }
  }
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const int a = i * (n + 1) + j, b = a + n + 1;
      mesh->triangles_.emplace_back(a, b, a + 1);
      mesh->triangles_.emplace_back(a + 1, b, b + 1);
    }
  }
  return mesh;
}

TEST(ObjectSurfaces, EachVoxelsSurfaceGoesToItsOwnerOnce) {
  // The wall's volume (id 1) covers y in [0, 2); the chair's volume (id 2)
  // covers y in [1, 1.5) on the same plane. Voxels with y in [1, 1.5) belong
  // to the chair (final id 2) and their surface is the wall volume's (most
  // views called them wall); the rest belong to the wall.
  fuse::MapResolution r;
  const double s = 0.05;
  for (int iy = 0; iy < 40; ++iy) {
    for (int iz = 0; iz < 20; ++iz) {
      const bool chair = iy >= 20 && iy < 30;
      r.owners[fuse::PackVoxel(0, iy, iz)] = {chair ? 2u : 1u, 1u};
    }
  }
  MeshMap volumes;
  volumes[1] = Sheet(0.01, 0.0, 2.0);
  volumes[2] = Sheet(0.012, 1.0, 0.5);
  const MeshMap cut = CutMeshesByOwner(volumes, r, s);
  ASSERT_EQ(cut.size(), 2u);
  // No wall triangle over the chair's voxels, none of the chair outside them.
  auto y_range = [](const open3d::geometry::TriangleMesh& m, bool inside) {
    size_t n = 0;
    for (const auto& t : m.triangles_) {
      const double y = (m.vertices_[t.x()].y() + m.vertices_[t.y()].y() +
                        m.vertices_[t.z()].y()) /
                       3.0;
      if ((y >= 1.0 && y < 1.5) == inside) ++n;
    }
    return n;
  };
  EXPECT_EQ(y_range(*cut.at(1), true), 0u);
  EXPECT_GT(y_range(*cut.at(1), false), 1000u);
  EXPECT_EQ(y_range(*cut.at(2), false), 0u);
  // The chair's surface comes from the wall's volume alone: the chair's own
  // sheet (x = 0.012) is not added on top of it.
  for (const auto& v : cut.at(2)->vertices_) EXPECT_DOUBLE_EQ(v.x(), 0.01);
  EXPECT_EQ(cut.at(2)->vertices_.size(), cut.at(2)->vertex_colors_.size());
  // Triangles beyond every owned voxel (z > 1 m) are left out.
  for (const auto& v : cut.at(1)->vertices_) EXPECT_LE(v.z(), 1.1);
}

TEST(ObjectSurfaces, VolumeWithoutMeshDoesNotLeaveAHole) {
  fuse::MapResolution r;
  for (int iy = 0; iy < 10; ++iy) {
    r.owners[fuse::PackVoxel(0, iy, 0)] = {3u, 9u};
  }
  MeshMap volumes;
  volumes[4] = Sheet(0.01, 0.0, 0.5);
  const MeshMap cut = CutMeshesByOwner(volumes, r, 0.05);
  ASSERT_EQ(cut.count(3), 1u);
  EXPECT_FALSE(cut.at(3)->triangles_.empty());
}

}  // namespace
}  // namespace semrec::pipeline
