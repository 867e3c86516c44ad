// Class tables as data files.
#pragma once

#include <filesystem>

#include "semrec/core/label_map.h"

namespace semrec::io {

/// Reads a JSON list of {"id": int, "name": string, "kind": "thing" | "stuff" |
/// "other", "color": [r, g, b]} (colour optional), with optional "structure":
/// "vertical" | "floor" | "ceiling" (stuff) and "footprint_m": [length, width]
/// (things; LabelClass). A list with neither key anywhere (written before they
/// were data, or by hand) takes them from the shipped sets (data/labels) by
/// class name. Throws FormatError naming the file and the class for malformed
/// entries, duplicates, a structure plane on a thing or a footprint on stuff.
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
