#include "semrec/mesh/tsdf_integrator.h"

#include <cstring>

#include <open3d/io/TriangleMeshIO.h>
#include <open3d/pipelines/integration/ScalableTSDFVolume.h>
#include <open3d/pipelines/integration/UniformTSDFVolume.h>

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

void TsdfIntegrator::Absorb(TsdfIntegrator* other) {
  CheckArgument(other != nullptr && other != this,
                "TsdfIntegrator::Absorb: needs another volume");
  CheckArgument(other->options_.voxel_size_m == options_.voxel_size_m &&
                    other->options_.sdf_trunc_m == options_.sdf_trunc_m &&
                    other->volume_->volume_unit_resolution_ ==
                        volume_->volume_unit_resolution_,
                "TsdfIntegrator::Absorb: volumes differ in voxel size, "
                "truncation or unit resolution");
  auto& units = volume_->volume_units_;
  for (auto& [index, unit] : other->volume_->volume_units_) {
    auto it = units.find(index);
    if (it == units.end()) {
      // Units are placed by their index alone: moving one is exact.
      units.emplace(index, std::move(unit));
      continue;
    }
    auto& into = it->second.volume_->voxels_;
    const auto& from = unit.volume_->voxels_;
    for (size_t v = 0; v < into.size(); ++v) {
      const float w_from = from[v].weight_;
      if (w_from <= 0.0f) continue;
      const float w_into = into[v].weight_;
      const float w = w_into + w_from;
      into[v].tsdf_ = (into[v].tsdf_ * w_into + from[v].tsdf_ * w_from) / w;
      into[v].color_ = (into[v].color_ * w_into + from[v].color_ * w_from) / w;
      into[v].weight_ = w;
    }
  }
  other->volume_->volume_units_.clear();
  num_integrated_ += other->num_integrated_;
  other->num_integrated_ = 0;
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
