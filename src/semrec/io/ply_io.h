// Minimal PLY I/O for point clouds and triangle meshes (binary little-endian on
// write; binary or ASCII vertex positions on read). Open3D, CloudCompare and
// MeshLab read what this writes.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace semrec::io {

struct PlyData {
  std::vector<Eigen::Vector3f> points;
  /// Optional, one per point.
  std::vector<std::array<uint8_t, 3>> colors;
  /// Optional per-point integer label (written as property `label`, uint32).
  std::vector<uint32_t> labels;
  /// Further named per-point integers (written as `int` properties after
  /// `label`; read from any other scalar vertex property), e.g. `semantic`
  /// and `instance` of a ground-truth cloud.
  std::vector<std::pair<std::string, std::vector<int32_t>>> int_properties;
  /// Optional triangles (indices into points).
  std::vector<std::array<uint32_t, 3>> triangles;
};

/// Writes atomically. Throws InvalidArgument when optional arrays are sized
/// inconsistently or triangles index out of range.
void WritePly(const std::filesystem::path& path, const PlyData& data);

/// Reads vertex positions (float or double x, y, z), colours (uchar
/// red/green/blue) and labels when present, and triangle faces. Throws
/// FormatError naming the file for anything malformed.
PlyData ReadPly(const std::filesystem::path& path);

}  // namespace semrec::io
