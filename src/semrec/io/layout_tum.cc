// TUM RGB-D: rgb.txt, depth.txt ("timestamp filename" lines) and
// groundtruth.txt
// ("timestamp tx ty tz qx qy qz qw"), depth in 1/5000 m. Frames are driven by
// depth timestamps; the nearest colour image and the pose interpolated at the
// depth time are associated.
#include <algorithm>
#include <cmath>
#include <sstream>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/io/image_io.h"
#include "semrec/io/layouts.h"
#include "semrec/io/pose_io.h"

namespace fs = std::filesystem;

namespace semrec::io::internal {
namespace {

struct StampedFile {
  double timestamp_s;
  fs::path path;
};

std::vector<StampedFile> ReadFileList(const fs::path& list) {
  std::istringstream in(ReadTextFile(list));
  std::vector<StampedFile> out;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream tokens(line);
    double t = 0;
    std::string name;
    if (!(tokens >> t >> name)) {
      throw FormatError(
          list,
          fmt::format("line {}: expected \"timestamp filename\"", line_number));
    }
    out.push_back({t, list.parent_path() / name});
  }
  if (out.empty()) throw FormatError(list, "lists no images");
  std::stable_sort(out.begin(), out.end(),
                   [](const StampedFile& a, const StampedFile& b) {
                     return a.timestamp_s < b.timestamp_s;
                   });
  return out;
}

// Intrinsics published for the TUM Freiburg sensors (vision.in.tum.de,
// "Intrinsic Camera Calibration"); the 525 default is the ROS default used for
// the "validation" sequences.
CameraIntrinsics TumDefaultIntrinsics(const fs::path& folder,
                                      std::string* source) {
  const std::string name = fs::absolute(folder).lexically_normal().string();
  if (name.find("freiburg1") != std::string::npos) {
    *source = "default TUM freiburg1";
    return {640, 480, 517.3, 516.5, 318.6, 255.3};
  }
  if (name.find("freiburg2") != std::string::npos) {
    *source = "default TUM freiburg2";
    return {640, 480, 520.9, 521.0, 325.1, 249.7};
  }
  if (name.find("freiburg3") != std::string::npos) {
    *source = "default TUM freiburg3";
    return {640, 480, 535.4, 539.2, 320.1, 247.6};
  }
  *source = "default TUM ROS (525)";
  return {640, 480, 525.0, 525.0, 319.5, 239.5};
}

}  // namespace

std::optional<SequenceIndex> IndexTum(const fs::path& folder,
                                      const SequenceReaderOptions& options) {
  if (!fs::is_regular_file(folder / "rgb.txt") ||
      !fs::is_regular_file(folder / "depth.txt")) {
    return std::nullopt;
  }
  const fs::path gt_path = folder / "groundtruth.txt";
  const bool has_poses = fs::is_regular_file(gt_path);
  if (!has_poses && options.require_poses) {
    throw IoError(gt_path, std::string("no camera poses: ") + kNoPoses);
  }
  const auto colors = ReadFileList(folder / "rgb.txt");
  const auto depths = ReadFileList(folder / "depth.txt");
  const auto poses =
      has_poses ? ReadTumTrajectory(gt_path) : std::vector<StampedPose>{};

  SequenceIndex index;
  index.layout = "tum";
  index.root = folder;
  index.depth_scale = 5000.0;
  index.pose_source = has_poses ? "groundtruth.txt" : "none";
  index.has_poses = has_poses;
  const ImageInfo first = ReadImageInfo(depths.front().path);
  if (!options.intrinsics_path.empty()) {
    index.intrinsics =
        ReadIntrinsicsFile(options.intrinsics_path, first.width, first.height);
    index.intrinsics_source = options.intrinsics_path.string();
  } else if (fs::is_regular_file(folder / "intrinsics.json")) {
    index.intrinsics = ReadOpen3dIntrinsics(folder / "intrinsics.json");
    index.intrinsics_source = "intrinsics.json";
  } else {
    index.intrinsics = TumDefaultIntrinsics(folder, &index.intrinsics_source);
    index.intrinsics.width = first.width;
    index.intrinsics.height = first.height;
    spdlog::warn("{}: no intrinsics file, using {}", folder.string(),
                 index.intrinsics_source);
  }

  size_t dropped = 0;
  const double tol = options.max_time_diff_s;
  for (const StampedFile& depth : depths) {
    // Nearest colour image in time.
    auto it = std::lower_bound(
        colors.begin(), colors.end(), depth.timestamp_s,
        [](const StampedFile& a, double t) { return a.timestamp_s < t; });
    const StampedFile* best = nullptr;
    for (auto c : {it, it == colors.begin() ? it : std::prev(it)}) {
      if (c == colors.end()) continue;
      if (best == nullptr ||
          std::abs(c->timestamp_s - depth.timestamp_s) <
              std::abs(best->timestamp_s - depth.timestamp_s)) {
        best = &*c;
      }
    }
    // Pose: interpolate between the bracketing samples when they are close in
    // time.
    auto p1 = std::lower_bound(
        poses.begin(), poses.end(), depth.timestamp_s,
        [](const StampedPose& a, double t) { return a.timestamp_s < t; });
    std::optional<Transform> pose;
    if (!has_poses) {
      pose = Transform();
    } else if (p1 != poses.end() &&
               std::abs(p1->timestamp_s - depth.timestamp_s) <= 1e-9) {
      pose = p1->T_world_camera;
    } else if (p1 != poses.end() && p1 != poses.begin()) {
      const auto p0 = std::prev(p1);
      const double gap = p1->timestamp_s - p0->timestamp_s;
      if (gap <= 10 * tol) {
        pose =
            Transform::Interpolate(p0->T_world_camera, p1->T_world_camera,
                                   (depth.timestamp_s - p0->timestamp_s) / gap);
      }
    }
    if (best == nullptr ||
        std::abs(best->timestamp_s - depth.timestamp_s) > tol || !pose) {
      ++dropped;
      continue;
    }
    FrameRecord record;
    record.color_path = best->path;
    record.depth_path = depth.path;
    record.T_world_camera = *pose;
    record.timestamp_s = depth.timestamp_s;
    index.frames.push_back(std::move(record));
  }
  if (index.frames.empty()) {
    throw FormatError(
        folder,
        fmt::format("no depth image could be associated with a colour image "
                    "and a pose within {} s",
                    tol));
  }
  if (dropped > 0) {
    spdlog::warn(
        "{}: {} of {} depth images have no colour image or pose within {} s; "
        "skipped",
        folder.string(), dropped, depths.size(), tol);
  }
  return index;
}

}  // namespace semrec::io::internal
