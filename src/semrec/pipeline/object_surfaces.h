// Meshes follow the map's final labels: each object's volume was integrated
// from the pixels fusion gave it while streaming, but the voxel evidence
// (fuse/map_objects.h) may move a place to another object at the end (a chair
// some views called wall). Each volume's mesh is cut by the voxel owners: a
// triangle goes to the object that owns the voxel nearest its centre, and only
// from the volume that holds that voxel's surface (the object most views put
// it in), so every surface appears once.
//
// A TSDF at 2 cm gives no surface where few views saw something thin (a lamp's
// 4 cm pole seen once spans two voxels: marching cubes finds no cube with all
// corners observed), yet the 5 cm map holds the pole's points. Voxels of
// things with no surface near them get a small patch there
// (CoverOwnedVoxels), so an object the map found is never missing from the
// scene, nor full of holes.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <unordered_map>

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

/// For each voxel of a thing in `resolution` (`evidence`: the map's voxels, at
/// `voxel_size_m`) whose labelled points' centroid has no vertex of any mesh
/// within `voxel_size_m`, adds to its owner's mesh a square patch of the
/// voxel's width at the centroid, facing the cameras that saw it
/// (VoxelEvidence::towards_camera_sum; up when unknown), coloured as the
/// owner's mesh on average (grey without one). Voxels with fewer than
/// `min_points` labelled points are left as they are. Returns the number of
/// patches added.
size_t CoverOwnedVoxels(
    const fuse::MapResolution& resolution,
    const std::unordered_map<uint64_t, fuse::VoxelEvidence>& evidence,
    double voxel_size_m, uint32_t min_points, MeshMap* meshes);

}  // namespace semrec::pipeline
