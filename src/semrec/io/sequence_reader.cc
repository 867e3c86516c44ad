#include "semrec/io/sequence_reader.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <yaml-cpp/yaml.h>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/io/image_io.h"
#include "semrec/io/layouts.h"
#include "semrec/io/pose_io.h"

namespace fs = std::filesystem;

namespace semrec::io {

void SequenceReaderOptions::Check() const {
  CheckArgument(
      stride >= 1,
      fmt::format("sequence reader: stride must be >= 1, got {}", stride));
  CheckArgument(std::isfinite(max_depth_m) && max_depth_m >= 0.0,
                "sequence reader: max_depth_m must be >= 0 (0 = no limit)");
  CheckArgument(max_time_diff_s > 0.0,
                "sequence reader: max_time_diff_s must be > 0");
  CheckArgument(std::isfinite(bag.sync_tol_ms) && bag.sync_tol_ms >= 0.0,
                "sequence reader: the bag sync tolerance must be >= 0 ms");
}

namespace internal {

std::vector<fs::path> ListFiles(const fs::path& folder,
                                const std::vector<std::string>& suffixes) {
  std::vector<fs::path> out;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    if (!entry.is_regular_file()) continue;
    std::string name = entry.path().filename().string();
    std::transform(name.begin(), name.end(), name.begin(),
                   [](unsigned char c) { return std::tolower(c); });
    for (const auto& suffix : suffixes) {
      if (name.size() >= suffix.size() &&
          name.compare(name.size() - suffix.size(), suffix.size(), suffix) ==
              0) {
        out.push_back(entry.path());
        break;
      }
    }
  }
  if (ec) throw IoError(folder, "cannot list folder: " + ec.message());
  std::sort(out.begin(), out.end());
  return out;
}

CameraIntrinsics ReadIntrinsicsFile(const fs::path& path, int width,
                                    int height) {
  if (path.extension() == ".json") return ReadOpen3dIntrinsics(path);
  return ReadIntrinsicsMatrixFile(path, width, height);
}

}  // namespace internal

std::optional<SequenceReader> SequenceReader::TryOpen(
    const fs::path& path, const SequenceReaderOptions& options) {
  options.Check();
  std::error_code ec;
  if (!fs::exists(path, ec)) return std::nullopt;
  std::optional<SequenceIndex> index = internal::IndexBag(path, options);
  if (!index) index = internal::IndexSens(path, options);
  if (!index) index = internal::IndexManifest(path, options);
  if (!index && fs::is_directory(path, ec)) {
    for (auto detect : {internal::IndexTum, internal::IndexRedwood,
                        internal::IndexSevenScenes}) {
      index = detect(path, options);
      if (index) break;
    }
  }
  if (!index) return std::nullopt;
  return SequenceReader(std::move(*index), options);
}

SequenceReader SequenceReader::Open(const fs::path& path,
                                    const SequenceReaderOptions& options) {
  options.Check();
  std::error_code ec;
  if (!fs::exists(path, ec)) {
    throw IoError(path, "sequence path does not exist");
  }
  std::optional<SequenceReader> reader = TryOpen(path, options);
  if (!reader) {
    throw IoError(
        path,
        "no known RGB-D layout found. Expected one of: a semrec manifest "
        "(sequence.yaml/.json), TUM (rgb.txt + depth.txt + groundtruth.txt), "
        "Redwood "
        "(color/ + depth/ + *.log), 7-Scenes/3DMatch (frame-XXXXXX.depth.png + "
        ".pose.txt), a ROS 2 bag (*.mcap, *.db3, or a folder with "
        "metadata.yaml), ScanNet "
        "*.sens. "
        "See docs/usage.md, 'Sequence layouts'.");
  }
  return std::move(*reader);
}

SequenceReader::SequenceReader(SequenceIndex index,
                               const SequenceReaderOptions& options)
    : index_(std::move(index)), options_(options) {
  options_.Check();
  if (index_.frames.empty()) {
    throw FormatError(index_.root, "sequence has no frames");
  }
  try {
    index_.intrinsics.Check();
  } catch (const InvalidArgument& e) {
    throw FormatError(index_.root, e.what());
  }
  CheckArgument(index_.depth_scale > 0.0,
                index_.root.string() + ": depth scale must be > 0");
  if (!options_.pose_correction_path.empty()) {
    const PoseCorrection correction =
        ReadPoseCorrection(options_.pose_correction_path);
    for (FrameRecord& frame : index_.frames) {
      frame.T_world_camera = correction.Apply(frame.T_world_camera);
    }
    index_.pose_source += " corrected by " + correction.source;
  }
  if (options_.stride > 1 || options_.max_frames > 0) {
    std::vector<FrameRecord> kept;
    for (size_t i = 0; i < index_.frames.size(); i += options_.stride) {
      if (options_.max_frames > 0 && kept.size() >= options_.max_frames) break;
      kept.push_back(std::move(index_.frames[i]));
    }
    index_.frames = std::move(kept);
  }
}

Frame SequenceReader::Read(size_t i) const {
  if (i >= size()) {
    throw InvalidArgument(
        fmt::format("{}: frame {} out of range (sequence has {})",
                    root().string(), i, size()));
  }
  const FrameRecord& record = index_.frames[i];
  Frame frame;
  frame.index = i;
  frame.timestamp_s = record.timestamp_s;
  frame.T_world_camera = record.T_world_camera;
  frame.intrinsics = index_.intrinsics;
  frame.color_path = record.color_path;
  frame.depth_path = record.depth_path;
  if (index_.source) {
    index_.source->Read(record.source_index, &frame.color, &frame.depth);
    if (options_.max_depth_m > 0.0) {
      for (float& d : frame.depth.values()) {
        if (d >= options_.max_depth_m) d = 0.0f;
      }
    }
    const CameraIntrinsics& k = index_.intrinsics;
    if (!frame.depth.SameSize(k.width, k.height) ||
        !frame.color.SameSize(frame.depth)) {
      throw FormatError(
          record.color_path,
          fmt::format("colour {}x{} and depth {}x{} do not match the camera "
                      "({}: {}x{})",
                      frame.color.width(), frame.color.height(),
                      frame.depth.width(), frame.depth.height(),
                      index_.intrinsics_source, k.width, k.height));
    }
    return frame;
  }
  const DepthImage16 raw = ReadDepthImage(record.depth_path);
  const CameraIntrinsics& k = index_.intrinsics;
  if (!raw.SameSize(k.width, k.height)) {
    throw FormatError(
        record.depth_path,
        fmt::format(
            "depth image is {}x{} but the camera intrinsics ({}) say {}x{}",
            raw.width(), raw.height(), index_.intrinsics_source, k.width,
            k.height));
  }
  frame.depth = DepthToMeters(raw, index_.depth_scale, index_.depth_invalid,
                              options_.max_depth_m);
  frame.color = ReadColorImage(record.color_path);
  if (!frame.color.SameSize(raw)) {
    throw FormatError(
        record.color_path,
        fmt::format("colour image is {}x{} but its depth image {} is {}x{}",
                    frame.color.width(), frame.color.height(),
                    record.depth_path.filename().string(), raw.width(),
                    raw.height()));
  }
  return frame;
}

double SequenceReader::TrajectoryLengthM() const {
  double length = 0.0;
  for (size_t i = 1; i < size(); ++i) {
    length +=
        (T_world_camera(i).translation() - T_world_camera(i - 1).translation())
            .norm();
  }
  return length;
}

void WriteSequenceManifest(const fs::path& manifest_path,
                           const SequenceIndex& index) {
  const fs::path base = manifest_path.parent_path();
  auto rel = [&](const fs::path& p) {
    const fs::path r = p.lexically_relative(base);
    return (r.empty() || *r.begin() == "..") ? p.string() : r.string();
  };
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "format" << YAML::Value << "semrec-sequence";
  out << YAML::Key << "version" << YAML::Value << 1;
  const CameraIntrinsics& k = index.intrinsics;
  out << YAML::Key << "intrinsics" << YAML::Value << YAML::Flow
      << YAML::BeginMap;
  out << YAML::Key << "width" << YAML::Value << k.width << YAML::Key << "height"
      << YAML::Value << k.height;
  out << YAML::Key << "fx" << YAML::Value << k.fx << YAML::Key << "fy"
      << YAML::Value << k.fy;
  out << YAML::Key << "cx" << YAML::Value << k.cx << YAML::Key << "cy"
      << YAML::Value << k.cy;
  out << YAML::EndMap;
  out << YAML::Key << "depth_scale" << YAML::Value << index.depth_scale;
  out << YAML::Key << "depth_invalid" << YAML::Value << index.depth_invalid;
  out << YAML::Key << "frames" << YAML::Value << YAML::BeginSeq;
  for (const FrameRecord& f : index.frames) {
    out << YAML::BeginMap;
    out << YAML::Key << "color" << YAML::Value << rel(f.color_path);
    out << YAML::Key << "depth" << YAML::Value << rel(f.depth_path);
    out << YAML::Key << "timestamp_s" << YAML::Value << f.timestamp_s;
    const Eigen::Matrix4d m = f.T_world_camera.Matrix();
    out << YAML::Key << "T_world_camera" << YAML::Value << YAML::Flow
        << YAML::BeginSeq;
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) out << m(r, c);
    }
    out << YAML::EndSeq;
    if (!f.layers.empty()) {
      out << YAML::Key << "layers" << YAML::Value << YAML::Flow
          << YAML::BeginMap;
      for (const auto& [name, path] : f.layers) {
        out << YAML::Key << name << YAML::Value << rel(path);
      }
      out << YAML::EndMap;
    }
    out << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::EndMap;
  WriteTextFileAtomic(manifest_path, std::string(out.c_str()) + "\n");
}

}  // namespace semrec::io
