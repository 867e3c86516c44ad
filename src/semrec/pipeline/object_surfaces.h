// Meshes follow the map's final labels: each object's volume was integrated
// from the pixels fusion gave it while streaming, but the voxel evidence
// (fuse/map_objects.h) may move a place to another object at the end (a chair
// some views called wall). Each volume's mesh is cut by the voxel owners: a
// triangle goes to the object that owns the voxel nearest its centre, and only
// from the volume that holds that voxel's surface (the object most views put
// it in), so every surface appears once.
#pragma once

#include <cstdint>
#include <map>
#include <memory>

#include <open3d/geometry/TriangleMesh.h>

#include "semrec/fuse/map_objects.h"

namespace semrec::pipeline {

using MeshMap =
    std::map<uint32_t, std::shared_ptr<open3d::geometry::TriangleMesh>>;

/// `volume_meshes`: meshes by volume (fusion object) id. Returns meshes by
/// final object id. Triangles farther than one voxel from every owned voxel
/// are left out.
MeshMap CutMeshesByOwner(const MeshMap& volume_meshes,
                         const fuse::MapResolution& resolution,
                         double voxel_size_m);

}  // namespace semrec::pipeline
