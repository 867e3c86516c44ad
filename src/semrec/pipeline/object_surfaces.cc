#include "semrec/pipeline/object_surfaces.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <unordered_map>
#include <utility>
#include <vector>

#include "semrec/fuse/voxel.h"
#include "semrec/fuse/voxel_votes.h"

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

// A square of side `size_m` centred on `centre`, facing `normal`, as a fan of
// four triangles around its centre (wound counter-clockwise seen from the
// normal's side).
void AddPatch(const Eigen::Vector3d& centre, const Eigen::Vector3d& normal,
              double size_m, const Eigen::Vector3d& color,
              open3d::geometry::TriangleMesh* mesh) {
  const Eigen::Vector3d u = normal.unitOrthogonal(), v = normal.cross(u);
  const double h = size_m / 2;
  const auto first = static_cast<int>(mesh->vertices_.size());
  mesh->vertices_.push_back(centre);
  for (const auto& [a, b] : {std::pair{1, 1}, {-1, 1}, {-1, -1}, {1, -1}}) {
    mesh->vertices_.push_back(centre + h * (a * u + b * v));
  }
  for (int k = 0; k < 5; ++k) {
    mesh->vertex_normals_.push_back(normal);
    mesh->vertex_colors_.push_back(color);
  }
  for (int k = 0; k < 4; ++k) {
    mesh->triangles_.emplace_back(first, first + 1 + k,
                                  first + 1 + (k + 1) % 4);
  }
}

}  // namespace

size_t CoverOwnedVoxels(
    const fuse::MapResolution& resolution,
    const std::unordered_map<uint64_t, fuse::VoxelEvidence>& evidence,
    double voxel_size_m, uint32_t min_points, MeshMap* meshes) {
  const double size_m = voxel_size_m;
  // Things' voxels by owner, in key order (the same patches every run).
  // Structure is left as its volumes show it: large planes a TSDF meshes
  // well, and a patch at a wall's edge would reach into the thing before it.
  std::set<uint32_t> things;
  for (const fuse::MapObject& o : resolution.objects) {
    if (o.kind != ClassKind::kStuff) things.insert(o.id);
  }
  std::map<uint32_t, std::vector<uint64_t>> voxels;
  for (const auto& [key, owner] : resolution.owners) {
    if (things.contains(owner.owner)) voxels[owner.owner].push_back(key);
  }
  // Any object's surface within a voxel of the points shows them already:
  // another object's surface there is theirs under another label (the
  // points' centroid lies a few cm off it with depth noise), and a patch
  // would take its place.
  fuse::Cloud vertices;
  for (const auto& [id, mesh] : *meshes) {
    if (!mesh) continue;
    for (const Eigen::Vector3d& v : mesh->vertices_) {
      vertices.push_back(v.cast<float>());
    }
  }
  const fuse::VoxelGrid grid(vertices, size_m);
  const auto max_d2 = static_cast<float>(size_m * size_m);
  auto covered = [&](const Eigen::Vector3d& p) {
    uint64_t computations = 0;
    return grid.Nearest(vertices, p.cast<float>(), max_d2, &computations)
               .index >= 0;
  };
  const open3d::geometry::TriangleMesh none;
  size_t added = 0;
  for (auto& [owner, keys] : voxels) {
    std::sort(keys.begin(), keys.end());
    // An owner without a mesh gets one only if it gets a patch.
    const auto found = meshes->find(owner);
    const open3d::geometry::TriangleMesh& mesh =
        found != meshes->end() && found->second ? *found->second : none;
    Eigen::Vector3d color(0.5, 0.5, 0.5);
    if (mesh.HasVertexColors()) {
      color.setZero();
      for (const Eigen::Vector3d& c : mesh.vertex_colors_) color += c;
      color /= static_cast<double>(mesh.vertex_colors_.size());
    }
    // Patches keep the mesh's attributes parallel to its vertices.
    const bool had_vertices = !mesh.vertices_.empty();
    const bool normals = !had_vertices || mesh.HasVertexNormals();
    const bool colors = !had_vertices || mesh.HasVertexColors();
    open3d::geometry::TriangleMesh patches;
    for (const uint64_t key : keys) {
      const auto it = evidence.find(key);
      if (it == evidence.end() || it->second.points < min_points) {
        continue;
      }
      const Eigen::Vector3d centre = it->second.Centroid().cast<double>();
      if (covered(centre)) continue;
      const Eigen::Vector3f seen = it->second.towards_camera_sum;
      const Eigen::Vector3d normal =
          seen.norm() > 1e-3f
              ? Eigen::Vector3d(seen.normalized().cast<double>())
              : Eigen::Vector3d(Eigen::Vector3d::UnitZ());
      AddPatch(centre, normal, size_m, color, &patches);
      ++added;
    }
    if (patches.triangles_.empty()) continue;
    auto& target = (*meshes)[owner];
    if (!target) target = std::make_shared<open3d::geometry::TriangleMesh>();
    open3d::geometry::TriangleMesh* out = target.get();
    const auto offset = static_cast<int>(out->vertices_.size());
    out->vertices_.insert(out->vertices_.end(), patches.vertices_.begin(),
                          patches.vertices_.end());
    if (normals) {
      out->vertex_normals_.insert(out->vertex_normals_.end(),
                                  patches.vertex_normals_.begin(),
                                  patches.vertex_normals_.end());
    }
    if (colors) {
      out->vertex_colors_.insert(out->vertex_colors_.end(),
                                 patches.vertex_colors_.begin(),
                                 patches.vertex_colors_.end());
    }
    for (const Eigen::Vector3i& t : patches.triangles_) {
      out->triangles_.push_back(t + Eigen::Vector3i::Constant(offset));
    }
  }
  return added;
}

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
