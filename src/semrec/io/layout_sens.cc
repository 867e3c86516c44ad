// ScanNet's .sens files (version 4): a header (sensor name, colour and depth
// intrinsics and extrinsics as 4x4 float matrices, compression types, image
// sizes, depth shift, frame count), then per frame the camera-to-world pose,
// colour and depth timestamps, and the compressed colour (JPEG or PNG) and
// depth (zlib-compressed or raw uint16) bytes. Frames with an invalid pose
// (-inf, as ScanNet marks lost tracking) are skipped and counted. Colour is
// resized to the depth image's size when they differ (1296x968 vs 640x480),
// and the frame's intrinsics are the depth camera's, which back-project the
// depth.
#include <zlib.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <mutex>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "semrec/core/error.h"
#include "semrec/io/image_io.h"
#include "semrec/io/layouts.h"

namespace fs = std::filesystem;

namespace semrec::io::internal {
namespace {

enum ColorCompression { kColorRaw = 0, kColorPng = 1, kColorJpeg = 2 };
enum DepthCompression { kDepthRaw = 0, kDepthZlib = 1 };
// Frames larger than this are refused (a 4K colour JPEG is ~2 MB).
constexpr uint64_t kMaxFrameBytes = uint64_t{256} << 20;

struct SensFrame {
  uint64_t color_offset = 0, color_size = 0;
  uint64_t depth_offset = 0, depth_size = 0;
};

struct SensHeader {
  std::string sensor;
  Eigen::Matrix4f color_k, depth_k;
  int32_t color_compression = 0, depth_compression = 0;
  uint32_t color_width = 0, color_height = 0, depth_width = 0, depth_height = 0;
  float depth_shift = 1000.0f;
  uint64_t frames = 0;
};

class SensFile {
 public:
  explicit SensFile(const fs::path& path)
      : path_(path), in_(path, std::ios::binary) {
    if (!in_) throw IoError(path, "cannot open the .sens file");
    in_.seekg(0, std::ios::end);
    size_ = static_cast<uint64_t>(in_.tellg());
    in_.seekg(0);
  }
  template <typename T>
  T Get(const char* what) {
    T v{};
    Bytes(reinterpret_cast<char*>(&v), sizeof(T), what);
    return v;
  }
  void Bytes(char* out, uint64_t n, const char* what) {
    if (n > size_ - Pos() || !in_.read(out, static_cast<std::streamsize>(n))) {
      throw FormatError(path_, fmt::format("truncated .sens file: it ends in "
                                           "the {} at byte {}",
                                           what, Pos()));
    }
  }
  Eigen::Matrix4f Matrix(const char* what) {
    Eigen::Matrix<float, 4, 4, Eigen::RowMajor> m;
    Bytes(reinterpret_cast<char*>(m.data()), 64, what);
    return m;
  }
  void Skip(uint64_t n, const char* what) {
    if (n > size_ - Pos()) {
      throw FormatError(path_, fmt::format("truncated .sens file: it ends in "
                                           "the {} at byte {}",
                                           what, Pos()));
    }
    in_.seekg(static_cast<std::streamoff>(n), std::ios::cur);
  }
  uint64_t Pos() { return static_cast<uint64_t>(in_.tellg()); }
  std::vector<uint8_t> Read(uint64_t offset, uint64_t n) {
    std::vector<uint8_t> out(n);
    in_.clear();
    in_.seekg(static_cast<std::streamoff>(offset));
    Bytes(reinterpret_cast<char*>(out.data()), n, "frame data");
    return out;
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
  std::ifstream in_;
  uint64_t size_ = 0;
};

SensHeader ReadHeader(SensFile* f) {
  const auto version = f->Get<uint32_t>("version");
  if (version != 4) {
    throw FormatError(f->path(), fmt::format(".sens version {} is not read "
                                             "(version 4 is)",
                                             version));
  }
  SensHeader h;
  const auto name_size = f->Get<uint64_t>("sensor name");
  if (name_size > 4096) {
    throw FormatError(f->path(), "the sensor name is implausibly long");
  }
  h.sensor.resize(name_size);
  f->Bytes(h.sensor.data(), name_size, "sensor name");
  h.color_k = f->Matrix("colour intrinsics");
  f->Matrix("colour extrinsics");
  h.depth_k = f->Matrix("depth intrinsics");
  f->Matrix("depth extrinsics");
  h.color_compression = f->Get<int32_t>("header");
  h.depth_compression = f->Get<int32_t>("header");
  h.color_width = f->Get<uint32_t>("header");
  h.color_height = f->Get<uint32_t>("header");
  h.depth_width = f->Get<uint32_t>("header");
  h.depth_height = f->Get<uint32_t>("header");
  h.depth_shift = f->Get<float>("header");
  h.frames = f->Get<uint64_t>("header");
  if (h.color_compression != kColorJpeg && h.color_compression != kColorPng &&
      h.color_compression != kColorRaw) {
    throw FormatError(f->path(), fmt::format("colour compression {} is not "
                                             "read (raw, png and jpeg are)",
                                             h.color_compression));
  }
  if (h.depth_compression != kDepthZlib && h.depth_compression != kDepthRaw) {
    throw FormatError(f->path(), fmt::format("depth compression {} is not "
                                             "read (raw and zlib are)",
                                             h.depth_compression));
  }
  if (h.depth_width == 0 || h.depth_height == 0 || h.depth_width > 16384 ||
      h.depth_height > 16384 || h.color_width > 16384 ||
      h.color_height > 16384 || !(h.depth_shift > 0.0f)) {
    throw FormatError(f->path(), "implausible image sizes or depth shift");
  }
  return h;
}

class SensFrames : public FrameSource {
 public:
  SensFrames(const fs::path& path, SensHeader header)
      : file_(path), header_(std::move(header)) {}

  std::vector<SensFrame> frames;

  void Read(size_t i, ColorImage* color, DepthImage* depth) const override {
    const SensFrame& f = frames.at(i);
    const uint32_t w = header_.depth_width, h = header_.depth_height;
    std::vector<uint8_t> raw, color_bytes;
    {
      // The file reads one at a time; decoding runs in parallel.
      std::lock_guard<std::mutex> lock(mutex_);
      raw = file_.Read(f.depth_offset, f.depth_size);
      color_bytes = file_.Read(f.color_offset, f.color_size);
    }
    std::vector<uint16_t> d(size_t{w} * h);
    uLongf n = static_cast<uLongf>(d.size() * 2);
    if (header_.depth_compression == kDepthZlib) {
      if (uncompress(reinterpret_cast<Bytef*>(d.data()), &n, raw.data(),
                     static_cast<uLong>(raw.size())) != Z_OK ||
          n != d.size() * 2) {
        throw FormatError(
            file_.path(),
            fmt::format("frame {}: the depth data is corrupt", i));
      }
    } else if (raw.size() == d.size() * 2) {
      std::memcpy(d.data(), raw.data(), raw.size());
    } else {
      throw FormatError(file_.path(),
                        fmt::format("frame {}: raw depth of {} bytes, not {}",
                                    i, raw.size(), d.size() * 2));
    }
    DepthImage16 mm(static_cast<int>(w), static_cast<int>(h));
    mm.values() = std::move(d);
    *depth = DepthToMeters(mm, header_.depth_shift);
    *color = DecodeColor(i, color_bytes);
  }

 private:
  ColorImage DecodeColor(size_t i, const std::vector<uint8_t>& raw) const {
    ColorImage decoded;
    if (header_.color_compression == kColorRaw) {
      if (raw.size() !=
          size_t{header_.color_width} * header_.color_height * 3) {
        throw FormatError(
            file_.path(),
            fmt::format("frame {}: raw colour of {} bytes", i, raw.size()));
      }
      decoded = ColorImage(static_cast<int>(header_.color_width),
                           static_cast<int>(header_.color_height), 3);
      decoded.values() = raw;
    } else {
      const fs::path source =
          file_.path().string() + fmt::format(" (frame {})", i);
      decoded = DecodeColorImage(raw, source);
    }
    const int w = static_cast<int>(header_.depth_width);
    const int h = static_cast<int>(header_.depth_height);
    if (decoded.SameSize(w, h)) return decoded;
    // Resized straight into the output (OpenCV views of both buffers).
    ColorImage out(w, h, 3);
    const cv::Mat src(decoded.height(), decoded.width(), CV_8UC3,
                      decoded.data());
    cv::Mat dst(h, w, CV_8UC3, out.data());
    cv::resize(src, dst, dst.size(), 0, 0, cv::INTER_AREA);
    return out;
  }

  mutable std::mutex mutex_;
  mutable SensFile file_;
  SensHeader header_;
};

fs::path FindSens(const fs::path& path) {
  std::error_code ec;
  if (fs::is_regular_file(path, ec)) {
    return path.extension() == ".sens" ? path : fs::path();
  }
  if (!fs::is_directory(path, ec)) return {};
  const auto files = ListFiles(path, {".sens"});
  return files.size() == 1 ? files[0] : fs::path();
}

}  // namespace

std::optional<SequenceIndex> IndexSens(const fs::path& path,
                                       const SequenceReaderOptions& options) {
  const fs::path file = FindSens(path);
  if (file.empty()) return std::nullopt;
  SensFile f(file);
  SensHeader h = ReadHeader(&f);
  SequenceIndex index;
  index.layout = "scannet-sens";
  index.root = path;
  const Eigen::Matrix4f& K = h.depth_k;
  index.intrinsics.width = static_cast<int>(h.depth_width);
  index.intrinsics.height = static_cast<int>(h.depth_height);
  index.intrinsics.fx = K(0, 0);
  index.intrinsics.fy = K(1, 1);
  index.intrinsics.cx = K(0, 2);
  index.intrinsics.cy = K(1, 2);
  index.intrinsics_source = file.filename().string() + " (depth intrinsics)";
  if (!options.intrinsics_path.empty()) {
    index.intrinsics =
        ReadIntrinsicsFile(options.intrinsics_path, index.intrinsics.width,
                           index.intrinsics.height);
    index.intrinsics_source = options.intrinsics_path.filename().string();
  }
  index.pose_source = file.filename().string() + " (camera to world)";
  index.depth_scale = h.depth_shift;
  auto frames = std::make_shared<SensFrames>(file, h);
  size_t invalid = 0;
  for (uint64_t i = 0; i < h.frames; ++i) {
    const Eigen::Matrix4f pose = f.Matrix("frame pose");
    const auto t_color = f.Get<uint64_t>("frame header");
    f.Get<uint64_t>("frame header");  // depth timestamp
    SensFrame s;
    s.color_size = f.Get<uint64_t>("frame header");
    s.depth_size = f.Get<uint64_t>("frame header");
    if (s.color_size > kMaxFrameBytes || s.depth_size > kMaxFrameBytes) {
      throw FormatError(file, fmt::format("frame {}: implausible data sizes "
                                          "({} and {} bytes)",
                                          i, s.color_size, s.depth_size));
    }
    s.color_offset = f.Pos();
    f.Skip(s.color_size, "colour data");
    s.depth_offset = f.Pos();
    f.Skip(s.depth_size, "depth data");
    if (!pose.allFinite()) {
      ++invalid;
      continue;
    }
    FrameRecord r;
    const size_t k = frames->frames.size();
    r.color_path = path / fmt::format("frame-{:06}.color.jpg", i);
    r.depth_path = path / fmt::format("frame-{:06}.depth.png", i);
    try {
      r.T_world_camera =
          Transform::FromMatrix(pose.cast<double>(), "frame pose", 1e-2);
    } catch (const InvalidArgument& e) {
      throw FormatError(file, fmt::format("frame {}: {}", i, e.what()));
    }
    r.timestamp_s = t_color > 0 ? 1e-6 * static_cast<double>(t_color)
                                : static_cast<double>(i) / 30.0;
    r.source_index = k;
    frames->frames.push_back(s);
    index.frames.push_back(std::move(r));
  }
  index.details.push_back(fmt::format(
      "sensor '{}': colour {}x{} ({}), depth {}x{} ({}), depth shift {}; {} "
      "frames, {} skipped with an invalid pose",
      h.sensor, h.color_width, h.color_height,
      h.color_compression == kColorJpeg  ? "jpeg"
      : h.color_compression == kColorPng ? "png"
                                         : "raw",
      h.depth_width, h.depth_height,
      h.depth_compression == kDepthZlib ? "zlib" : "raw", h.depth_shift,
      h.frames, invalid));
  if (h.color_width != h.depth_width || h.color_height != h.depth_height) {
    index.details.push_back("colour resized to the depth size");
  }
  if (index.frames.empty()) {
    throw FormatError(file, "no frame with a valid pose");
  }
  index.source = std::move(frames);
  return index;
}

}  // namespace semrec::io::internal
