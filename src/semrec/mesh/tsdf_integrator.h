// Whole-scene TSDF integration with Open3D's ScalableTSDFVolume (the `semrec
// tsdf` command and the reference for later per-object meshing).
#pragma once

#include <filesystem>
#include <memory>

#include <open3d/camera/PinholeCameraIntrinsic.h>
#include <open3d/geometry/RGBDImage.h>
#include <open3d/geometry/TriangleMesh.h>

#include "semrec/core/frame.h"

namespace open3d::pipelines::integration {
class ScalableTSDFVolume;
}

namespace semrec::mesh {

struct TsdfOptions {
  /// Voxel edge length. 1 cm resolves furniture-scale detail from 640x480
  /// depth.
  double voxel_size_m = 0.01;
  /// Truncation distance of the signed distance field; ~4 voxels is the usual
  /// choice.
  double sdf_trunc_m = 0.04;
  /// Depths at or beyond this are ignored (sensor noise grows quadratically
  /// with depth).
  double max_depth_m = 4.0;
  /// Integrate colour (RGB8) along with geometry.
  bool integrate_color = true;

  /// Throws InvalidArgument unless all sizes are positive and sdf_trunc_m >
  /// voxel_size_m.
  void Check() const;
};

/// Open3D views of our types. Depth is passed in metres (depth_scale 1).
open3d::camera::PinholeCameraIntrinsic ToOpen3d(
    const CameraIntrinsics& intrinsics);
/// RGBD image in Open3D's convention (colour as float intensity only when
/// !keep_color_rgb).
std::shared_ptr<open3d::geometry::RGBDImage> ToOpen3dRgbd(
    const Frame& frame, double max_depth_m,
    bool convert_rgb_to_intensity = false);

class TsdfIntegrator {
 public:
  explicit TsdfIntegrator(const TsdfOptions& options = {});
  ~TsdfIntegrator();
  TsdfIntegrator(const TsdfIntegrator&) = delete;
  TsdfIntegrator& operator=(const TsdfIntegrator&) = delete;

  /// Integrates one frame at its pose (T_world_camera).
  void Integrate(const Frame& frame);
  /// Marching-cubes mesh of the current volume (vertex colours when
  /// integrate_color).
  std::shared_ptr<open3d::geometry::TriangleMesh> ExtractMesh() const;
  size_t num_integrated() const { return num_integrated_; }

  /// Adds `other`'s volume to this one as if its frames had been integrated
  /// here: per voxel, TSDF and colour are averaged weighted by the voxels'
  /// weights and the weights add (exactly what integrating those frames does,
  /// up to floating-point rounding). `other` must have the same voxel size and
  /// truncation; it is left empty. Lets a streaming pipeline combine the
  /// volumes of two objects that fusion merges after both were integrated.
  void Absorb(TsdfIntegrator* other);

 private:
  TsdfOptions options_;
  std::unique_ptr<open3d::pipelines::integration::ScalableTSDFVolume> volume_;
  size_t num_integrated_ = 0;
};

/// Writes a mesh as binary PLY atomically. Throws IoError on failure.
void WriteMeshPly(const std::filesystem::path& path,
                  const open3d::geometry::TriangleMesh& mesh);

}  // namespace semrec::mesh
