// USDZ packaging (the USDZ specification): an uncompressed, unencrypted zip
// archive whose file data each start at a multiple of 64 bytes, so a reader
// can map the layers in place. The first file is the stage's root layer.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace semrec::usd {

/// CRC-32 (IEEE 802.3, the zip checksum) of `data`.
uint32_t Crc32(const std::string& data);

/// Bytes of a USDZ archive holding `files` (name inside the package, content)
/// in the given order. Names must be relative, without "..", unique, and the
/// first must be a .usda/.usdc/.usd layer. Throws InvalidArgument otherwise.
std::string UsdzBytes(
    const std::vector<std::pair<std::string, std::string>>& files);

/// Writes UsdzBytes(files) to `path` atomically.
void WriteUsdz(const std::filesystem::path& path,
               const std::vector<std::pair<std::string, std::string>>& files);

}  // namespace semrec::usd
