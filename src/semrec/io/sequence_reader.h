// RGB-D sequences on disk. `SequenceReader::Open(path)` detects the layout
// (semrec manifest, TUM RGB-D, Redwood/Open3D, 7-Scenes/3DMatch), validates the
// index (files, poses, counts) up front, and reads frames on demand with full
// checks (decodable images, 16-bit depth, sizes).
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "semrec/core/camera.h"
#include "semrec/core/frame.h"
#include "semrec/core/image.h"
#include "semrec/core/transform.h"

namespace semrec::io {

/// ROS 2 bags (MCAP or SQLite rosbag2): which topics and frames make the
/// RGB-D frames. Empty = chosen from the bag (see docs/usage.md, "ROS 2 bags").
struct BagOptions {
  std::string color_topic;
  std::string depth_topic;
  std::string camera_info_topic;
  /// "tf" (the camera frame in the TF tree) or a topic of
  /// nav_msgs/msg/Odometry or geometry_msgs/msg/PoseStamped.
  std::string pose_source = "tf";
  /// Empty: "map", then "odom", then the root of the camera's TF tree.
  std::string world_frame;
  /// Empty: the colour image's header.frame_id.
  std::string camera_frame;
  /// Colour and depth pair up when their stamps differ by at most this.
  double sync_tol_ms = 20.0;
};

struct SequenceReaderOptions {
  /// Use every `stride`-th frame of the dataset.
  int stride = 1;
  /// Use at most this many frames (after the stride); 0 = all.
  size_t max_frames = 0;
  /// Depths at or beyond this are marked invalid; 0 = keep all.
  double max_depth_m = 0.0;
  /// Overrides the layout's intrinsics: an Open3D JSON (`*.json`) or a 3x3 K
  /// matrix text file.
  std::filesystem::path intrinsics_path;
  /// TUM: maximum time difference (s) when associating colour, depth and poses.
  double max_time_diff_s = 0.02;
  /// Redwood: trajectory file name inside the folder; empty = odometry.log,
  /// then trajectory.log.
  std::string pose_file;
  /// A pose correction (YAML, see io::ReadPoseCorrection) applied to every
  /// pose: T_world_camera = pre * T_file * post. For datasets whose poses
  /// are not the camera's (e.g. data/poses/bonn_rgbd_dynamic.yaml).
  std::filesystem::path pose_correction_path;
  BagOptions bag;
  /// A recording without poses is refused (false: its frames are read with
  /// identity poses and SequenceIndex::has_poses false, for pose
  /// estimation; TUM, Redwood and 7-Scenes / 3DMatch folders).
  bool require_poses = true;

  /// Throws InvalidArgument for out-of-range values.
  void Check() const;
};

/// One frame's files and pose, as listed by the layout.
struct FrameRecord {
  std::filesystem::path color_path;
  std::filesystem::path depth_path;
  Transform T_world_camera;
  double timestamp_s = 0.0;
  /// Extra per-frame images by name (e.g. "semantic", "instance", "person"),
  /// generic layout only.
  std::map<std::string, std::filesystem::path> layers;
  /// The frame's number in the index's FrameSource (bags: the paths above
  /// are names only, under the bag's path).
  size_t source_index = 0;
};

/// Frames that are not image files (messages in a bag): the layout decodes
/// them. Safe to call from several threads.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  /// Colour (RGB8) and depth in metres (0 = none) of frame `i`. Throws
  /// FormatError naming the file and message.
  virtual void Read(size_t i, ColorImage* color, DepthImage* depth) const = 0;
};

/// What a layout detector found: everything needed to read frames.
struct SequenceIndex {
  /// "semrec", "tum", "redwood" or "7scenes".
  std::string layout;
  std::filesystem::path root;
  CameraIntrinsics intrinsics;
  /// Raw depth units per metre (1000 for millimetres, 5000 for TUM).
  double depth_scale = 1000.0;
  /// A raw depth value that means "no measurement" besides 0 (7-Scenes uses
  /// 65535); 0 = none.
  uint16_t depth_invalid = 0;
  /// Where the poses came from (file name), for reports ("none" without).
  std::string pose_source;
  /// False when the recording has no poses (read with require_poses off):
  /// every T_world_camera is the identity.
  bool has_poses = true;
  /// Where the intrinsics came from (file name or "default ..."), for reports.
  std::string intrinsics_source;
  std::vector<FrameRecord> frames;
  /// Set when frames are decoded by the layout rather than read from files.
  std::shared_ptr<const FrameSource> source;
  /// What the layout chose and found, for `semrec info` (bags: topics,
  /// TF chain, pairing).
  std::vector<std::string> details;
};

class SequenceReader {
 public:
  /// Opens `path` (a folder, or a semrec manifest file), auto-detecting the
  /// layout. Throws IoError for a missing path or an unknown layout,
  /// FormatError for a broken one (names the file).
  static SequenceReader Open(const std::filesystem::path& path,
                             const SequenceReaderOptions& options = {});

  /// Like Open, but nullopt (instead of an error) when `path` does not exist
  /// or is in no known layout; a sequence in a known layout but broken still
  /// throws, naming what is wrong.
  static std::optional<SequenceReader> TryOpen(
      const std::filesystem::path& path,
      const SequenceReaderOptions& options = {});

  /// Wraps an index built elsewhere (validated here: non-empty, consistent).
  SequenceReader(SequenceIndex index, const SequenceReaderOptions& options);

  const std::string& layout() const { return index_.layout; }
  const std::filesystem::path& root() const { return index_.root; }
  size_t size() const { return index_.frames.size(); }
  const CameraIntrinsics& intrinsics() const { return index_.intrinsics; }
  const SequenceIndex& index() const { return index_; }
  const Transform& T_world_camera(size_t i) const {
    return index_.frames.at(i).T_world_camera;
  }

  /// Reads frame `i`: colour (RGB8), metric depth, pose, intrinsics. Throws
  /// FormatError naming the file for corrupt images, non-16-bit depth, or sizes
  /// that disagree with each other or with the intrinsics.
  Frame Read(size_t i) const;

  /// Total camera path length in metres (sum of distances between consecutive
  /// positions).
  double TrajectoryLengthM() const;

 private:
  SequenceIndex index_;
  SequenceReaderOptions options_;
};

/// Writes a generic-layout manifest (`sequence.yaml`) atomically; paths are
/// stored relative to the manifest's folder when they lie inside it. See
/// docs/usage.md, "Generic layout".
void WriteSequenceManifest(const std::filesystem::path& manifest_path,
                           const SequenceIndex& index);

}  // namespace semrec::io
