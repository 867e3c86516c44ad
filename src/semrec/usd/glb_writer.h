// glTF 2.0 binary (.glb) export of a reconstructed scene, for the tools that do
// not read USD (Blender, three.js, most web and game engines). Same content as
// the USD layers: one node per object named like its USD prim (`<class>_<id>`,
// structure by class), vertex colours, and the class, instance id and kind in
// the node's `extras`; people as nodes whose translation follows their centroid
// and whose scale drops to 0 in frames they are out of view (STEP animation); their cloud is
// their fullest observation.
// glTF is Y-up and in metres: a Z-up stage is rotated (-90 degrees about X) and
// scaled by metersPerUnit in the root node "World".
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "semrec/usd/usda_writer.h"

namespace semrec::usd {

/// The scene as GLB bytes. Throws InvalidArgument for inconsistent meshes (an
/// index out of range, normals or colours of the wrong count) or invalid stage
/// options.
std::string GlbBytes(const std::vector<MeshPrim>& meshes,
                     const StageOptions& options,
                     const std::vector<PersonTrack>& people = {});

/// Writes GlbBytes as `path`, atomically. Throws IoError for an unwritable
/// path.
void WriteSceneGlb(const std::filesystem::path& path,
                   const std::vector<MeshPrim>& meshes,
                   const StageOptions& options,
                   const std::vector<PersonTrack>& people = {});

}  // namespace semrec::usd
