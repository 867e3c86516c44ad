#include "semrec/io/image_io.h"

#include <png.h>

#include <algorithm>
#include <cctype>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"

namespace fs = std::filesystem;

namespace semrec::io {
namespace {

bool IsPng(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext == ".png";
}

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

cv::Mat ReadWithOpenCv(const fs::path& path, int flags) {
  RequireFile(path, "image");
  const std::vector<unsigned char> bytes = ReadFileBytes(path);
  if (bytes.empty()) throw FormatError(path, "image file is empty");
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
  cv::Mat bgr = ReadWithOpenCv(path, cv::IMREAD_COLOR);
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  ColorImage out(rgb.cols, rgb.rows, 3);
  for (int y = 0; y < rgb.rows; ++y) {
    std::memcpy(&out(0, y), rgb.ptr<uint8_t>(y),
                static_cast<size_t>(rgb.cols) * 3);
  }
  return out;
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
  cv::Mat mat = ReadWithOpenCv(path, cv::IMREAD_ANYDEPTH);
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
