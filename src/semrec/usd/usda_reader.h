// Reads back the USDA scenes semrec writes (not a general USD parser): the
// meshes of a static layer, or of the layers a root layer sublayers, and a
// layer's customLayerData.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "semrec/usd/usda_writer.h"

namespace semrec::usd {

/// Mesh prims with points, triangles, labels and provenance. Given a root
/// layer, follows its subLayers (relative paths). Throws FormatError naming the
/// file for text it cannot read.
std::vector<MeshPrim> ReadScene(const std::filesystem::path& path);

/// The customLayerData entries of one layer (not of its subLayers), name ->
/// value; string values unquoted, others as written. Empty when the layer has
/// none. Reads only the layer's metadata, not its prims. Throws IoError for a
/// file it cannot open, FormatError naming the file for a broken header.
std::map<std::string, std::string> ReadCustomLayerData(
    const std::filesystem::path& path);

}  // namespace semrec::usd
