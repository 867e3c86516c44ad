#include "semrec/pipeline/object_surfaces.h"

#include <cmath>
#include <limits>
#include <unordered_map>
#include <vector>

#include "semrec/fuse/voxel.h"
#include "semrec/fuse/voxel_evidence.h"

namespace semrec::pipeline {
namespace {

// The owned voxel nearest to `p` among its own and the 26 around it (by voxel
// centre), or nullptr.
const fuse::VoxelOwner* NearestOwner(
    const Eigen::Vector3d& p, double voxel_size_m,
    const std::unordered_map<uint64_t, fuse::VoxelOwner>& owners) {
  const Eigen::Vector3d q = p / voxel_size_m;
  const Eigen::Vector3i c(static_cast<int>(std::floor(q.x())),
                          static_cast<int>(std::floor(q.y())),
                          static_cast<int>(std::floor(q.z())));
  if (const auto it = owners.find(fuse::PackVoxel(c.x(), c.y(), c.z()));
      it != owners.end()) {
    return &it->second;
  }
  const fuse::VoxelOwner* best = nullptr;
  double best_d2 = std::numeric_limits<double>::infinity();
  for (int dx = -1; dx <= 1; ++dx) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dz = -1; dz <= 1; ++dz) {
        const Eigen::Vector3i n = c + Eigen::Vector3i(dx, dy, dz);
        const auto it = owners.find(fuse::PackVoxel(n.x(), n.y(), n.z()));
        if (it == owners.end()) continue;
        const double d2 =
            (n.cast<double>() + Eigen::Vector3d::Constant(0.5) - q)
                .squaredNorm();
        if (d2 < best_d2) best_d2 = d2, best = &it->second;
      }
    }
  }
  return best;
}

// Builds each output mesh from the triangles routed to it, vertices re-indexed.
class MeshCollector {
 public:
  explicit MeshCollector(const open3d::geometry::TriangleMesh& source)
      : source_(source) {}
  void Add(uint32_t owner, const Eigen::Vector3i& t, MeshMap* out) {
    auto& mesh = (*out)[owner];
    if (!mesh) mesh = std::make_shared<open3d::geometry::TriangleMesh>();
    auto& remap = remaps_[owner];
    Eigen::Vector3i nt;
    for (int k = 0; k < 3; ++k) {
      const auto [it, added] =
          remap.try_emplace(t[k], static_cast<int>(mesh->vertices_.size()));
      if (added) {
        mesh->vertices_.push_back(source_.vertices_[t[k]]);
        if (source_.HasVertexNormals()) {
          mesh->vertex_normals_.push_back(source_.vertex_normals_[t[k]]);
        }
        if (source_.HasVertexColors()) {
          mesh->vertex_colors_.push_back(source_.vertex_colors_[t[k]]);
        }
      }
      nt[k] = it->second;
    }
    mesh->triangles_.push_back(nt);
  }

 private:
  const open3d::geometry::TriangleMesh& source_;
  std::map<uint32_t, std::unordered_map<int, int>> remaps_;
};

}  // namespace

MeshMap CutMeshesByOwner(const MeshMap& volume_meshes,
                         const fuse::MapResolution& resolution,
                         double voxel_size_m) {
  MeshMap out;
  // A voxel whose surface volume has no mesh (too few observations) takes its
  // triangles from any volume rather than leaving a hole.
  auto meshed = [&](uint32_t id) {
    const auto it = volume_meshes.find(id);
    return it != volume_meshes.end() && it->second &&
           !it->second->triangles_.empty();
  };
  for (const auto& [volume, mesh] : volume_meshes) {
    if (!mesh) continue;
    MeshCollector collector(*mesh);
    for (const Eigen::Vector3i& t : mesh->triangles_) {
      const Eigen::Vector3d centre =
          (mesh->vertices_[t.x()] + mesh->vertices_[t.y()] +
           mesh->vertices_[t.z()]) /
          3.0;
      const fuse::VoxelOwner* owner =
          NearestOwner(centre, voxel_size_m, resolution.owners);
      if (owner == nullptr || owner->owner == 0 ||
          (owner->source != volume && meshed(owner->source))) {
        continue;
      }
      collector.Add(owner->owner, t, &out);
    }
  }
  return out;
}

}  // namespace semrec::pipeline
