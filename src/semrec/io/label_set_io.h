// Class tables as data files.
#pragma once

#include <filesystem>

#include "semrec/core/label_map.h"

namespace semrec::io {

/// Reads a JSON list of {"id": int, "name": string, "color": [r, g, b]} (colour
/// optional). Throws FormatError naming the file for malformed entries or
/// duplicates.
LabelSet ReadLabelSetJson(const std::filesystem::path& path);

/// Writes the same format atomically.
void WriteLabelSetJson(const std::filesystem::path& path,
                       const LabelSet& labels);

}  // namespace semrec::io
