// Class tables as data files.
#pragma once

#include <filesystem>

#include "semrec/core/label_map.h"

namespace semrec::io {

/// Reads a JSON list of {"id": int, "name": string, "color": [r, g, b]} (colour
/// optional). Throws FormatError naming the file for malformed entries or
/// duplicates.
LabelSet ReadLabelSetJson(const std::filesystem::path& path);

/// A label set by name ("voc"/"voc21", "ade20k"/"ade20k150", "coco"/"coco80",
/// "cityscapes"/"cityscapes19"; files in ProjectDataDir()/labels, see
/// core/file_util.h) or by the
/// path of a JSON file in the ReadLabelSetJson format. Throws InvalidArgument
/// for an unknown name that is not a file either.
LabelSet LoadLabelSet(const std::string& name_or_path);

/// Writes the same format atomically.
void WriteLabelSetJson(const std::filesystem::path& path,
                       const LabelSet& labels);

}  // namespace semrec::io
