#include "semrec/mesh/tsdf_integrator.h"

#include <cstring>

#include <open3d/io/TriangleMeshIO.h>
#include <open3d/pipelines/integration/ScalableTSDFVolume.h>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"

namespace semrec::mesh {

void TsdfOptions::Check() const {
  CheckArgument(voxel_size_m > 0.0, "tsdf: voxel_size_m must be > 0");
  CheckArgument(sdf_trunc_m > voxel_size_m,
                "tsdf: sdf_trunc_m must be larger than voxel_size_m (usually "
                "3-5 voxels)");
  CheckArgument(max_depth_m > 0.0, "tsdf: max_depth_m must be > 0");
}

open3d::camera::PinholeCameraIntrinsic ToOpen3d(const CameraIntrinsics& k) {
  return open3d::camera::PinholeCameraIntrinsic(k.width, k.height, k.fx, k.fy,
                                                k.cx, k.cy);
}

std::shared_ptr<open3d::geometry::RGBDImage> ToOpen3dRgbd(
    const Frame& frame, double max_depth_m, bool convert_rgb_to_intensity) {
  CheckArgument(
      frame.color.SameSize(frame.depth) && frame.color.channels() == 3,
      "ToOpen3dRgbd: colour must be RGB8 of the depth's size");
  open3d::geometry::Image color, depth;
  color.Prepare(frame.color.width(), frame.color.height(), 3, 1);
  std::memcpy(color.data_.data(), frame.color.data(), color.data_.size());
  depth.Prepare(frame.depth.width(), frame.depth.height(), 1, 4);
  std::memcpy(depth.data_.data(), frame.depth.data(), depth.data_.size());
  return open3d::geometry::RGBDImage::CreateFromColorAndDepth(
      color, depth, /*depth_scale=*/1.0, max_depth_m, convert_rgb_to_intensity);
}

TsdfIntegrator::TsdfIntegrator(const TsdfOptions& options) : options_(options) {
  options_.Check();
  using open3d::pipelines::integration::TSDFVolumeColorType;
  volume_ =
      std::make_unique<open3d::pipelines::integration::ScalableTSDFVolume>(
          options_.voxel_size_m, options_.sdf_trunc_m,
          options_.integrate_color ? TSDFVolumeColorType::RGB8
                                   : TSDFVolumeColorType::NoColor);
}

TsdfIntegrator::~TsdfIntegrator() = default;

void TsdfIntegrator::Integrate(const Frame& frame) {
  const auto rgbd = ToOpen3dRgbd(frame, options_.max_depth_m);
  // Open3D takes the extrinsic as world-to-camera.
  volume_->Integrate(*rgbd, ToOpen3d(frame.intrinsics),
                     frame.T_world_camera.Inverse().Matrix());
  ++num_integrated_;
}

std::shared_ptr<open3d::geometry::TriangleMesh> TsdfIntegrator::ExtractMesh()
    const {
  return volume_->ExtractTriangleMesh();
}

void WriteMeshPly(const std::filesystem::path& path,
                  const open3d::geometry::TriangleMesh& mesh) {
  WriteFileAtomic(path, [&](const std::filesystem::path& tmp) {
    if (!open3d::io::WriteTriangleMesh(
            tmp.string(), mesh, /*write_ascii=*/false,
            /*compressed=*/false, /*write_vertex_normals=*/true,
            /*write_vertex_colors=*/true)) {
      throw IoError(path, "cannot write mesh (folder writable? disk full?)");
    }
  });
}

}  // namespace semrec::mesh
