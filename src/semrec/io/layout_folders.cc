// Folder-of-files layouts: Redwood/Open3D (color/, depth/, *.log) and 7-Scenes
// / 3DMatch / tsdf-fusion (frame-XXXXXX.{color.jpg|color.png, depth.png,
// pose.txt}).
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <fstream>
#include <map>
#include <sstream>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/io/image_io.h"
#include "semrec/io/layouts.h"
#include "semrec/io/pose_io.h"

namespace fs = std::filesystem;

namespace semrec::io::internal {
namespace {

// Nominal frame rate for layouts without timestamps (Kinect-class sensors).
constexpr double kNominalRateHz = 30.0;

// Redwood's optional rgbd.match: "depth/xxx.png color/xxx.jpg" per line.
std::vector<std::pair<fs::path, fs::path>> ReadRgbdMatch(
    const fs::path& match) {
  std::istringstream in(ReadTextFile(match));
  std::vector<std::pair<fs::path, fs::path>> pairs;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    std::istringstream tokens(line);
    std::string depth, color;
    if (!(tokens >> depth)) continue;
    if (!(tokens >> color)) {
      throw FormatError(
          match, fmt::format("line {}: expected \"depth_file color_file\"",
                             line_number));
    }
    pairs.emplace_back(match.parent_path() / depth,
                       match.parent_path() / color);
  }
  return pairs;
}

}  // namespace

std::optional<SequenceIndex> IndexRedwood(
    const fs::path& folder, const SequenceReaderOptions& options) {
  const fs::path color_dir = folder / "color";
  const fs::path depth_dir = folder / "depth";
  if (!fs::is_directory(color_dir) || !fs::is_directory(depth_dir)) {
    return std::nullopt;
  }

  SequenceIndex index;
  index.layout = "redwood";
  index.root = folder;
  std::vector<fs::path> colors, depths;
  if (fs::is_regular_file(folder / "rgbd.match")) {
    for (auto& [d, c] : ReadRgbdMatch(folder / "rgbd.match")) {
      depths.push_back(d);
      colors.push_back(c);
    }
  } else {
    colors = ListFiles(color_dir, {".jpg", ".jpeg", ".png"});
    depths = ListFiles(depth_dir, {".png"});
  }
  if (depths.empty()) {
    throw FormatError(depth_dir, "no depth images (*.png) in folder");
  }
  if (colors.size() != depths.size()) {
    throw FormatError(
        folder,
        fmt::format("{} colour images in color/ but {} depth images in depth/",
                    colors.size(), depths.size()));
  }

  fs::path pose_path;
  if (!options.pose_file.empty()) {
    pose_path = folder / options.pose_file;
    RequireFile(pose_path, "trajectory");
  } else {
    for (const char* name : {"odometry.log", "trajectory.log"}) {
      if (fs::is_regular_file(folder / name)) {
        pose_path = folder / name;
        break;
      }
    }
    if (pose_path.empty()) {
      const auto logs = ListFiles(folder, {".log"});
      if (logs.empty() && options.require_poses) {
        throw IoError(folder / "odometry.log",
                      std::string("no trajectory file (odometry.log, "
                                  "trajectory.log or *.log) in the folder: ") +
                          kNoPoses);
      }
      if (!logs.empty()) pose_path = logs.front();
    }
  }
  index.has_poses = !pose_path.empty();
  const std::vector<Transform> poses =
      index.has_poses ? ReadRedwoodLog(pose_path)
                      : std::vector<Transform>(depths.size());
  if (poses.size() != depths.size()) {
    throw FormatError(
        pose_path,
        fmt::format("{} poses for {} frames: counts of frames and poses "
                    "must match",
                    poses.size(), depths.size()));
  }
  index.pose_source = index.has_poses ? pose_path.filename().string() : "none";

  const ImageInfo first = ReadImageInfo(depths.front());
  if (!options.intrinsics_path.empty()) {
    index.intrinsics =
        ReadIntrinsicsFile(options.intrinsics_path, first.width, first.height);
    index.intrinsics_source = options.intrinsics_path.string();
  } else {
    fs::path json;
    for (const char* name : {"camera_primesense.json", "camera_intrinsic.json",
                             "intrinsic.json", "intrinsics.json"}) {
      if (fs::is_regular_file(folder / name)) {
        json = folder / name;
        break;
      }
    }
    if (!json.empty()) {
      index.intrinsics = ReadOpen3dIntrinsics(json);
      index.intrinsics_source = json.filename().string();
    } else {
      // Open3D's PrimeSenseDefault, the camera of the Redwood datasets.
      index.intrinsics = {first.width, first.height, 525.0,
                          525.0,       319.5,        239.5};
      index.intrinsics_source = "default PrimeSense (525)";
      spdlog::warn("{}: no intrinsics JSON, using {}", folder.string(),
                   index.intrinsics_source);
    }
  }
  for (size_t i = 0; i < depths.size(); ++i) {
    FrameRecord record;
    record.color_path = colors[i];
    record.depth_path = depths[i];
    record.T_world_camera = poses[i];
    record.timestamp_s = static_cast<double>(i) / kNominalRateHz;
    index.frames.push_back(std::move(record));
  }
  return index;
}

std::optional<SequenceIndex> IndexSevenScenes(
    const fs::path& folder, const SequenceReaderOptions& options) {
  // Frames in the folder itself, or (3DMatch) in its seq-XX subfolders, taken
  // in order.
  std::vector<fs::path> depths = ListFiles(folder, {".depth.png"});
  if (depths.empty()) {
    std::vector<fs::path> seqs;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(folder, ec)) {
      if (entry.is_directory() &&
          entry.path().filename().string().rfind("seq-", 0) == 0) {
        seqs.push_back(entry.path());
      }
    }
    std::sort(seqs.begin(), seqs.end());
    for (const fs::path& seq : seqs) {
      for (fs::path& d : ListFiles(seq, {".depth.png"})) {
        depths.push_back(std::move(d));
      }
    }
  }
  if (depths.empty()) return std::nullopt;

  SequenceIndex index;
  index.layout = "7scenes";
  index.root = folder;
  index.depth_invalid = 65535;
  index.pose_source = "frame-*.pose.txt";
  const ImageInfo first = ReadImageInfo(depths.front());
  fs::path k_path = options.intrinsics_path;
  if (k_path.empty()) {
    for (const fs::path& candidate :
         {folder / "camera-intrinsics.txt",
          depths.front().parent_path() / "camera-intrinsics.txt"}) {
      if (fs::is_regular_file(candidate)) {
        k_path = candidate;
        break;
      }
    }
  }
  if (!k_path.empty()) {
    index.intrinsics = ReadIntrinsicsFile(k_path, first.width, first.height);
    index.intrinsics_source = k_path.filename().string();
  } else {
    // The 7-Scenes Kinect's published intrinsics.
    index.intrinsics = {first.width, first.height, 585.0, 585.0, 320.0, 240.0};
    index.intrinsics_source = "default 7-Scenes (585)";
    spdlog::warn("{}: no camera-intrinsics.txt, using {}", folder.string(),
                 index.intrinsics_source);
  }
  for (size_t i = 0; i < depths.size(); ++i) {
    const std::string name = depths[i].filename().string();
    const std::string stem =
        name.substr(0, name.size() - std::string(".depth.png").size());
    const fs::path dir = depths[i].parent_path();
    FrameRecord record;
    record.depth_path = depths[i];
    for (const char* ext : {".color.png", ".color.jpg"}) {
      if (fs::is_regular_file(dir / (stem + ext))) {
        record.color_path = dir / (stem + ext);
        break;
      }
    }
    if (record.color_path.empty()) {
      throw IoError(dir / (stem + ".color.png"),
                    "colour image missing for " + name +
                        " (expected .color.png or .color.jpg)");
    }
    const fs::path pose = dir / (stem + ".pose.txt");
    if (i == 0 && !fs::is_regular_file(pose)) {
      if (options.require_poses) {
        throw IoError(pose, std::string("no camera poses: ") + kNoPoses);
      }
      // No poses at all: for estimation.
      index.has_poses = false;
      index.pose_source = "none";
    }
    if (!index.has_poses) {
      record.timestamp_s = static_cast<double>(i) / kNominalRateHz;
      index.frames.push_back(std::move(record));
      continue;
    }
    if (!fs::is_regular_file(pose)) {
      throw FormatError(
          pose,
          fmt::format("pose file missing for {}: {} depth images but fewer "
                      "poses (counts of frames and poses must match)",
                      name, depths.size()));
    }
    record.T_world_camera = ReadPoseMatrixFile(pose);
    record.timestamp_s = static_cast<double>(i) / kNominalRateHz;
    index.frames.push_back(std::move(record));
  }
  return index;
}

}  // namespace semrec::io::internal
