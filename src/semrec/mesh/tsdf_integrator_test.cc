#include "semrec/mesh/tsdf_integrator.h"

#include <open3d/pipelines/integration/UniformTSDFVolume.h>

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/testing/test_util.h"

namespace semrec::mesh {
namespace {

// Open3D's own reference (../shared/data/README.md): integrating the 5 Redwood
// frames with these exact settings gives 3198 vertices and 4402 triangles.
// Matching it proves our reader (image decoding, depth scale, pose convention,
// intrinsics) feeds Open3D exactly what its test does.
TEST(RedwoodReference, UniformTsdfReproducesOpen3dCounts) {
  SEMREC_REQUIRE_SAMPLE_DATA(dir, "redwood_livingroom1_5");
  const io::SequenceReader reader = io::SequenceReader::Open(dir);
  ASSERT_EQ(reader.size(), 5u);
  open3d::pipelines::integration::UniformTSDFVolume volume(
      4.0, 100, 0.04,
      open3d::pipelines::integration::TSDFVolumeColorType::RGB8);
  for (size_t i = 0; i < reader.size(); ++i) {
    const Frame frame = reader.Read(i);
    volume.Integrate(*ToOpen3dRgbd(frame, /*max_depth_m=*/4.0),
                     ToOpen3d(frame.intrinsics),
                     frame.T_world_camera.Inverse().Matrix());
  }
  const auto mesh = volume.ExtractTriangleMesh();
  EXPECT_EQ(mesh->vertices_.size(), 3198u);
  EXPECT_EQ(mesh->triangles_.size(), 4402u);
  Eigen::Vector3d color_sum = Eigen::Vector3d::Zero();
  for (const auto& c : mesh->vertex_colors_) color_sum += c;
  EXPECT_NEAR(color_sum.x(), 2703.84, 0.01);
  EXPECT_NEAR(color_sum.y(), 2561.48, 0.01);
  EXPECT_NEAR(color_sum.z(), 2481.50, 0.01);
  EXPECT_EQ(volume.ExtractPointCloud()->points_.size(), 2227u);
}

// A camera at a known pose looking at a fronto-parallel wall: the mesh lies on
// the wall.
TEST(TsdfIntegrator, PlaneLandsAtItsWorldPosition) {
  Frame frame;
  frame.intrinsics = {64, 48, 50.0, 50.0, 31.5, 23.5};
  frame.color = ColorImage(64, 48, 3, 128);
  frame.depth = DepthImage(64, 48, 1, 1.5f);
  // Camera at (1, 2, 3), rotated 90 degrees about world y: camera z points
  // along world +x.
  frame.T_world_camera = Transform(
      Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix(),
      {1, 2, 3});
  TsdfOptions options;
  options.voxel_size_m = 0.02;
  options.sdf_trunc_m = 0.08;
  TsdfIntegrator tsdf(options);
  tsdf.Integrate(frame);
  tsdf.Integrate(frame);
  EXPECT_EQ(tsdf.num_integrated(), 2u);
  const auto mesh = tsdf.ExtractMesh();
  ASSERT_GT(mesh->vertices_.size(), 100u);
  for (const auto& v : mesh->vertices_) {
    EXPECT_NEAR(v.x(), 2.5, 0.01);  // 1 + 1.5 m
  }
}

TEST(TsdfOptions, Check) {
  TsdfOptions options;
  EXPECT_NO_THROW(options.Check());
  options.sdf_trunc_m = options.voxel_size_m / 2;
  EXPECT_THROW(options.Check(), InvalidArgument);
  options = {};
  options.max_depth_m = 0;
  EXPECT_THROW(options.Check(), InvalidArgument);
}

TEST(WriteMeshPly, WritesReadablePly) {
  testing::TempDir dir;
  open3d::geometry::TriangleMesh mesh;
  mesh.vertices_ = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.triangles_ = {{0, 1, 2}};
  WriteMeshPly(dir / "m.ply", mesh);
  EXPECT_GT(std::filesystem::file_size(dir / "m.ply"), 0u);
  EXPECT_THROW(WriteMeshPly("/proc/forbidden/m.ply", mesh), Error);
}

}  // namespace
}  // namespace semrec::mesh
