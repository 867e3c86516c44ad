// Reads back the USDA scenes semrec writes (not a general USD parser): the
// meshes of a static layer, or of the layers a root layer sublayers.
#pragma once

#include <filesystem>
#include <vector>

#include "semrec/usd/usda_writer.h"

namespace semrec::usd {

/// Mesh prims with points, triangles, labels and provenance. Given a root
/// layer, follows its subLayers (relative paths). Throws FormatError naming the
/// file for text it cannot read.
std::vector<MeshPrim> ReadScene(const std::filesystem::path& path);

}  // namespace semrec::usd
