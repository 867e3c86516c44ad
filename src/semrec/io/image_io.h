// Reading and writing images. PNG goes through libpng (8- and 16-bit, exact
// errors); JPEG and the netpbm formats (PPM/PGM) through OpenCV. Errors name
// the file and the problem.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "semrec/core/image.h"
#include "semrec/core/label_map.h"

namespace semrec::io {

/// The largest image the readers decode (64 megapixels, e.g. 8192 x 8192): a
/// header claiming more is refused before anything is allocated.
inline constexpr int64_t kMaxImagePixels = int64_t{1} << 26;

/// Reads a colour image (PNG, JPEG, PPM, ...) as 8-bit RGB. Grey images are
/// expanded to RGB and alpha is dropped. 16-bit colour PNGs are reduced to 8
/// bits.
ColorImage ReadColorImage(const std::filesystem::path& path);

/// Reads a single-channel 16-bit depth image (PNG or PGM). Throws FormatError
/// for 8-bit or multi-channel files: those are not depth maps and silently
/// scaling them would be wrong.
DepthImage16 ReadDepthImage(const std::filesystem::path& path);

/// Decode an image held in memory (PNG or JPEG bytes: a message in a bag, a
/// frame of a .sens file) with the checks of the file readers (sizes before
/// allocating); `source` names it in errors.
ColorImage DecodeColorImage(const std::vector<uint8_t>& bytes,
                            const std::filesystem::path& source);
DepthImage16 DecodeDepthImage(const std::vector<uint8_t>& bytes,
                              const std::filesystem::path& source);

/// Reads a single-channel 8- or 16-bit PNG as labels.
LabelMap ReadLabelImage(const std::filesystem::path& path);

/// Writes PNG atomically. Colour: 1, 3 or 4 channels of 8 bits. 16-bit: 1
/// channel.
void WritePng(const std::filesystem::path& path, const Image<uint8_t>& image);
void WritePng(const std::filesystem::path& path, const Image<uint16_t>& image);

/// Image size without decoding the pixels (PNG header or OpenCV fallback).
struct ImageInfo {
  int width = 0;
  int height = 0;
  int channels = 0;
  int bit_depth = 0;
};
ImageInfo ReadImageInfo(const std::filesystem::path& path);

}  // namespace semrec::io
