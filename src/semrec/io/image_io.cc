#include "semrec/io/image_io.h"

#include <png.h>

#include <algorithm>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"

namespace fs = std::filesystem;

namespace semrec::io {
namespace {

bool IsPng(const fs::path& path) { return LowerExtension(path) == ".png"; }

// Decoded PNG, channels interleaved, 16-bit samples in host order.
struct PngData {
  int width = 0;
  int height = 0;
  int channels = 0;
  int bit_depth = 0;
  std::vector<uint8_t> data8;
  std::vector<uint16_t> data16;
};

struct PngErrorState {
  std::string message;
};

void PngErrorFn(png_structp png, png_const_charp message) {
  auto* state = static_cast<PngErrorState*>(png_get_error_ptr(png));
  if (state != nullptr) state->message = message;
  png_longjmp(png, 1);
}
void PngWarningFn(png_structp, png_const_charp) {}

struct FileCloser {
  void operator()(std::FILE* f) const {
    if (f != nullptr) std::fclose(f);
  }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;

void CheckPixels(const fs::path& path, int64_t width, int64_t height) {
  if (width <= 0 || height <= 0 || width > kMaxImagePixels / height) {
    throw FormatError(path,
                      fmt::format("image header says {} x {} pixels, "
                                  "beyond the limit of {} megapixels",
                                  width, height, kMaxImagePixels / (1 << 20)));
  }
}

PngData ReadPng(const fs::path& path, bool header_only = false) {
  RequireFile(path, "image");
  FilePtr file(std::fopen(path.c_str(), "rb"));
  if (!file) throw IoError(path, "cannot open image for reading");
  png_byte signature[8] = {};
  if (std::fread(signature, 1, 8, file.get()) != 8 ||
      png_sig_cmp(signature, 0, 8) != 0) {
    throw FormatError(
        path, "not a PNG file (bad signature; truncated or mislabelled?)");
  }
  PngErrorState state;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &state,
                                           PngErrorFn, PngWarningFn);
  if (png == nullptr) throw Error("libpng: out of memory");
  png_infop info = png_create_info_struct(png);
  PngData out;
  // libpng reports errors by longjmp; everything with a destructor lives
  // outside this frame.
  std::vector<png_bytep> rows;
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    throw FormatError(path, "corrupt PNG: " + state.message);
  }
  png_init_io(png, file.get());
  png_set_sig_bytes(png, 8);
  png_read_info(png, info);
  const int color_type = png_get_color_type(png, info);
  int bit_depth = png_get_bit_depth(png, info);
  if (color_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (color_type == PNG_COLOR_TYPE_GRAY && bit_depth < 8) {
    png_set_expand_gray_1_2_4_to_8(png);
  }
  if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png);
  if (bit_depth == 16) {
    png_set_swap(png);  // PNG is big-endian; we want host order.
  }
  png_read_update_info(png, info);
  out.width = static_cast<int>(png_get_image_width(png, info));
  out.height = static_cast<int>(png_get_image_height(png, info));
  // Before allocating the raster: the header's size within limits, and not
  // more than zlib can inflate from the file (at most ~1032:1).
  const int64_t raw_bytes =
      (static_cast<int64_t>(png_get_rowbytes(png, info)) + 1) * out.height;
  std::error_code size_ec;
  const auto file_bytes = static_cast<int64_t>(fs::file_size(path, size_ec));
  if (int64_t{out.width} * out.height > kMaxImagePixels ||
      raw_bytes > 1100 * file_bytes + 4096) {
    png_destroy_read_struct(&png, &info, nullptr);
    CheckPixels(path, out.width, out.height);  // the shared limit first
    throw FormatError(path, fmt::format("PNG header says {} x {} pixels, "
                                        "more than the file holds",
                                        out.width, out.height));
  }
  out.channels = png_get_channels(png, info);
  out.bit_depth = bit_depth = png_get_bit_depth(png, info);
  if (!header_only) {
    const size_t row_bytes = png_get_rowbytes(png, info);
    rows.resize(out.height);
    if (bit_depth == 16) {
      out.data16.resize(static_cast<size_t>(out.width) * out.height *
                        out.channels);
      for (int y = 0; y < out.height; ++y) {
        rows[y] = reinterpret_cast<png_bytep>(out.data16.data() +
                                              static_cast<size_t>(y) *
                                                  out.width * out.channels);
      }
    } else {
      out.data8.resize(row_bytes * out.height);
      for (int y = 0; y < out.height; ++y) {
        rows[y] = out.data8.data() + row_bytes * y;
      }
    }
    png_read_image(png, rows.data());
    png_read_end(png, nullptr);
  }
  png_destroy_read_struct(&png, &info, nullptr);
  return out;
}

// Width and height from a JPEG's start-of-frame marker; nullopt when the
// markers end before one.
std::optional<std::pair<int, int>> JpegSize(
    const std::vector<unsigned char>& b) {
  size_t i = 2;
  while (i + 4 <= b.size()) {
    if (b[i] != 0xFF) return std::nullopt;
    const unsigned char marker = b[i + 1];
    if (marker == 0xFF) {  // fill byte
      ++i;
      continue;
    }
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD8)) {
      i += 2;  // markers without a length
      continue;
    }
    const size_t length = (b[i + 2] << 8) | b[i + 3];
    const bool sof = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 &&
                     marker != 0xC8 && marker != 0xCC;
    if (sof) {
      if (i + 9 > b.size()) return std::nullopt;
      return std::make_pair((b[i + 7] << 8) | b[i + 8],
                            (b[i + 5] << 8) | b[i + 6]);
    }
    if (marker == 0xDA || length < 2) return std::nullopt;  // scan data
    i += 2 + length;
  }
  return std::nullopt;
}

// Netpbm (P1-P6): the header's width and height, and whether the raster's
// size is at least what they promise.
void CheckNetpbm(const fs::path& path, const std::vector<unsigned char>& b) {
  size_t i = 2;
  auto next_number = [&]() -> int64_t {
    while (i < b.size()) {
      if (b[i] == '#') {
        while (i < b.size() && b[i] != '\n') ++i;
      } else if (std::isspace(b[i])) {
        ++i;
      } else {
        break;
      }
    }
    int64_t v = 0;
    const size_t start = i;
    while (i < b.size() && std::isdigit(b[i]) && v < (int64_t{1} << 40)) {
      v = v * 10 + (b[i++] - '0');
    }
    if (i == start) throw FormatError(path, "corrupt PGM/PPM header");
    return v;
  };
  const char kind = static_cast<char>(b[1]);
  const int64_t width = next_number(), height = next_number();
  CheckPixels(path, width, height);
  const int64_t max_value = (kind == '1' || kind == '4') ? 1 : next_number();
  const int64_t channels = (kind == '3' || kind == '6') ? 3 : 1;
  const int64_t samples = width * height * channels;
  // Raw rasters have a known size; ASCII ones take two characters a sample.
  const int64_t need = kind == '4'   ? (width + 7) / 8 * height
                       : kind >= '5' ? samples * (max_value > 255 ? 2 : 1)
                                     : samples * 2 - 1;
  if (static_cast<int64_t>(b.size() - i) < need) {
    throw FormatError(path, fmt::format("PGM/PPM of {} x {} pixels is "
                                        "truncated",
                                        width, height));
  }
}

cv::Mat DecodeWithOpenCv(const fs::path& path,
                         const std::vector<unsigned char>& bytes, int flags) {
  if (bytes.empty()) throw FormatError(path, "image data is empty");
  // OpenCV picks a decoder by content from every codec it was built with
  // (DICOM, OpenEXR, JPEG 2000, ...), some of which abort on crafted files:
  // only the formats semrec reads get through, sizes checked first.
  const bool png = bytes.size() >= 8 && png_sig_cmp(bytes.data(), 0, 8) == 0;
  const bool jpeg = bytes.size() >= 3 && bytes[0] == 0xFF && bytes[1] == 0xD8 &&
                    bytes[2] == 0xFF;
  const bool netpbm = bytes.size() >= 2 && bytes[0] == 'P' && bytes[1] >= '1' &&
                      bytes[1] <= '6';
  if (jpeg) {
    const auto size = JpegSize(bytes);
    if (!size) {
      throw FormatError(path,
                        "cannot decode image: corrupt JPEG (no frame header)");
    }
    CheckPixels(path, size->first, size->second);
  } else if (png) {
    // IHDR: width and height, big endian, after the signature and chunk head.
    if (bytes.size() < 24) throw FormatError(path, "truncated PNG header");
    auto be32 = [&](size_t at) {
      return (int64_t{bytes[at]} << 24) | (int64_t{bytes[at + 1]} << 16) |
             (int64_t{bytes[at + 2]} << 8) | int64_t{bytes[at + 3]};
    };
    CheckPixels(path, be32(16), be32(20));
  } else if (netpbm) {
    CheckNetpbm(path, bytes);
  } else if (!png) {
    throw FormatError(path,
                      "not an image semrec reads (PNG, JPEG, PGM/PPM) or "
                      "corrupt");
  }
  cv::Mat mat;
  try {
    mat = cv::imdecode(bytes, flags);
  } catch (const cv::Exception& e) {
    throw FormatError(path, std::string("cannot decode image: ") + e.what());
  }
  if (mat.empty()) {
    throw FormatError(
        path, "cannot decode image (corrupt, truncated or unsupported format)");
  }
  return mat;
}

cv::Mat ReadWithOpenCv(const fs::path& path, int flags) {
  RequireFile(path, "image");
  return DecodeWithOpenCv(path, ReadFileBytes(path), flags);
}

ColorImage BgrToColor(const cv::Mat& bgr) {
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  ColorImage out(rgb.cols, rgb.rows, 3);
  for (int y = 0; y < rgb.rows; ++y) {
    std::memcpy(&out(0, y), rgb.ptr<uint8_t>(y),
                static_cast<size_t>(rgb.cols) * 3);
  }
  return out;
}

DepthImage16 MatToDepth(const fs::path& path, const cv::Mat& mat) {
  if (mat.type() != CV_16UC1) {
    throw FormatError(
        path, "depth image must be single-channel 16-bit (OpenCV type " +
                  std::to_string(mat.type()) + ")");
  }
  DepthImage16 out(mat.cols, mat.rows, 1);
  for (int y = 0; y < mat.rows; ++y) {
    std::memcpy(&out(0, y), mat.ptr<uint16_t>(y),
                static_cast<size_t>(mat.cols) * 2);
  }
  return out;
}

template <typename T>
void WritePngImpl(const fs::path& path, const Image<T>& image, int bit_depth) {
  const int channels = image.channels();
  CheckArgument(!image.empty(), "WritePng: empty image for " + path.string());
  int color_type = 0;
  switch (channels) {
    case 1:
      color_type = PNG_COLOR_TYPE_GRAY;
      break;
    case 2:
      color_type = PNG_COLOR_TYPE_GRAY_ALPHA;
      break;
    case 3:
      color_type = PNG_COLOR_TYPE_RGB;
      break;
    case 4:
      color_type = PNG_COLOR_TYPE_RGB_ALPHA;
      break;
    default:
      throw InvalidArgument("WritePng: unsupported channel count for " +
                            path.string());
  }
  WriteFileAtomic(path, [&](const fs::path& tmp) {
    FilePtr file(std::fopen(tmp.c_str(), "wb"));
    if (!file) throw IoError(tmp, "cannot open for writing");
    PngErrorState state;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &state,
                                              PngErrorFn, PngWarningFn);
    if (png == nullptr) throw Error("libpng: out of memory");
    png_infop info = png_create_info_struct(png);
    std::vector<png_bytep> rows(image.height());
    if (setjmp(png_jmpbuf(png))) {
      png_destroy_write_struct(&png, &info);
      throw IoError(path, "PNG write failed: " + state.message);
    }
    png_init_io(png, file.get());
    // Level 1 compresses depth/label maps well at a fraction of the default's
    // time.
    png_set_compression_level(png, 1);
    // One fixed filter: libpng's adaptive choice tries all five per row and
    // costs more than the compression itself; SUB suits depth and label maps.
    png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
    png_set_IHDR(png, info, image.width(), image.height(), bit_depth,
                 color_type, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    if (bit_depth == 16) png_set_swap(png);
    for (int y = 0; y < image.height(); ++y) {
      rows[y] = reinterpret_cast<png_bytep>(const_cast<T*>(
          image.data() + static_cast<size_t>(y) * image.width() * channels));
    }
    png_write_image(png, rows.data());
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    if (std::fflush(file.get()) != 0) {
      throw IoError(path, "write failed (disk full?)");
    }
  });
}

}  // namespace

ColorImage ReadColorImage(const fs::path& path) {
  if (IsPng(path)) {
    const PngData png = ReadPng(path);
    ColorImage out(png.width, png.height, 3);
    const size_t n = out.NumPixels();
    for (size_t i = 0; i < n; ++i) {
      for (int c = 0; c < 3; ++c) {
        // Grey (1-2 channels) expands to RGB; alpha is dropped.
        const int src_c = png.channels >= 3 ? c : 0;
        const size_t src = i * png.channels + src_c;
        out.values()[i * 3 + c] =
            png.bit_depth == 16 ? static_cast<uint8_t>(png.data16[src] >> 8)
                                : png.data8[src];
      }
    }
    return out;
  }
  return BgrToColor(ReadWithOpenCv(path, cv::IMREAD_COLOR));
}

ColorImage DecodeColorImage(const std::vector<uint8_t>& bytes,
                            const fs::path& source) {
  return BgrToColor(DecodeWithOpenCv(source, bytes, cv::IMREAD_COLOR));
}

DepthImage16 DecodeDepthImage(const std::vector<uint8_t>& bytes,
                              const fs::path& source) {
  return MatToDepth(source,
                    DecodeWithOpenCv(source, bytes, cv::IMREAD_ANYDEPTH));
}

DepthImage16 ReadDepthImage(const fs::path& path) {
  if (IsPng(path)) {
    const PngData png = ReadPng(path);
    if (png.channels != 1 || png.bit_depth != 16) {
      throw FormatError(path,
                        "depth image must be single-channel 16-bit, got " +
                            std::to_string(png.channels) + " channel(s) of " +
                            std::to_string(png.bit_depth) + " bits");
    }
    DepthImage16 out(png.width, png.height, 1);
    out.values() = png.data16;
    return out;
  }
  return MatToDepth(path, ReadWithOpenCv(path, cv::IMREAD_ANYDEPTH));
}

LabelMap ReadLabelImage(const fs::path& path) {
  const PngData png = ReadPng(path);
  if (png.channels != 1) {
    throw FormatError(path, "label image must be single-channel, got " +
                                std::to_string(png.channels) + " channels");
  }
  LabelMap out(png.width, png.height, 1);
  if (png.bit_depth == 16) {
    out.values() = png.data16;
  } else {
    std::copy(png.data8.begin(), png.data8.end(), out.values().begin());
  }
  return out;
}

void WritePng(const fs::path& path, const Image<uint8_t>& image) {
  WritePngImpl(path, image, 8);
}

void WritePng(const fs::path& path, const Image<uint16_t>& image) {
  CheckArgument(image.channels() == 1,
                "WritePng: 16-bit images must have one channel");
  WritePngImpl(path, image, 16);
}

ImageInfo ReadImageInfo(const fs::path& path) {
  if (IsPng(path)) {
    const PngData png = ReadPng(path, /*header_only=*/true);
    return {png.width, png.height, png.channels, png.bit_depth};
  }
  const cv::Mat mat = ReadWithOpenCv(path, cv::IMREAD_UNCHANGED);
  return {mat.cols, mat.rows, mat.channels(), mat.depth() == CV_16U ? 16 : 8};
}

}  // namespace semrec::io
