// Layout detectors used by SequenceReader::Open. Each returns std::nullopt when
// `folder` is not in its layout, and throws FormatError/IoError when it is but
// something is broken.
#pragma once

#include <filesystem>
#include <optional>

#include "semrec/io/sequence_reader.h"

namespace semrec::io::internal {

/// What a sequence without poses is told when poses are required.
inline constexpr const char* kNoPoses =
    "this recording has no camera poses: let semrec estimate them "
    "(--poses estimate, or --poses auto: the recording's poses where it has "
    "them), or store a trajectory in the layout's pose file";

/// ROS 2 bags: a *.mcap file, or a folder with metadata.yaml or *.mcap.
std::optional<SequenceIndex> IndexBag(const std::filesystem::path& path,
                                      const SequenceReaderOptions& options);
/// ScanNet .sens (version 4): the file, or a folder holding exactly one.
std::optional<SequenceIndex> IndexSens(const std::filesystem::path& path,
                                       const SequenceReaderOptions& options);
std::optional<SequenceIndex> IndexManifest(
    const std::filesystem::path& path, const SequenceReaderOptions& options);
std::optional<SequenceIndex> IndexTum(const std::filesystem::path& folder,
                                      const SequenceReaderOptions& options);
std::optional<SequenceIndex> IndexRedwood(const std::filesystem::path& folder,
                                          const SequenceReaderOptions& options);
std::optional<SequenceIndex> IndexSevenScenes(
    const std::filesystem::path& folder, const SequenceReaderOptions& options);

/// Intrinsics from an explicit file: Open3D JSON for *.json, otherwise a 3x3 K
/// matrix text file (then width/height come from `width`, `height`).
CameraIntrinsics ReadIntrinsicsFile(const std::filesystem::path& path,
                                    int width, int height);

/// Sorted regular files in `folder` whose names end with one of `suffixes`
/// (case-insensitive).
std::vector<std::filesystem::path> ListFiles(
    const std::filesystem::path& folder,
    const std::vector<std::string>& suffixes);

}  // namespace semrec::io::internal
