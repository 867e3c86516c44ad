// Test helper: ROS 2 bags written from RGB-D frames as a robot would record
// them: colour and depth images with CameraInfo, and the camera's pose only
// as a TF chain map -> odom -> base_link -> camera_link ->
// camera_color_optical_frame (map -> odom drifting, odom -> base_link moving,
// the rest static).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "semrec/core/camera.h"
#include "semrec/core/image.h"
#include "semrec/core/transform.h"

namespace semrec::io::testing {

struct BagFrame {
  ColorImage color;
  /// Metres (0 = none); written as 16UC1 millimetres unless float_depth.
  DepthImage depth_m;
  Transform T_world_camera;
  double timestamp_s = 0.0;
};

struct TestBagOptions {
  /// "mcap" or "sqlite3".
  std::string storage = "mcap";
  /// MCAP chunk compression: "", "zstd" or "lz4".
  std::string compression = "zstd";
  bool chunk_crc = true;
  /// Colour as CompressedImage (jpeg) instead of Image (rgb8).
  bool compressed_color = false;
  /// Depth as image_transport's compressedDepth (png).
  bool compressed_depth = false;
  /// Depth as 32FC1 metres (exact) instead of 16UC1 millimetres.
  bool float_depth = false;
  /// Colour as bgr8 (raw images only).
  bool bgr = false;
  /// Depth stamps are the colour stamps plus this.
  double depth_offset_ms = 3.0;
  /// Write /tf (off: a bag without poses).
  bool tf = true;
  /// Also write /odom (nav_msgs/msg/Odometry, base_link in map), the
  /// pose source for `--pose-source /odom`.
  bool odometry = false;
  /// Write the depth topic (off: a bag without depth).
  bool depth = true;
  /// Depth in its own optical frame "camera_depth_optical_frame", this far
  /// to the colour camera's right (0: depth aligned to colour, as
  /// aligned_depth_to_color). The depth images given are then the depth
  /// camera's (same intrinsics).
  double depth_baseline_m = 0.0;
  /// Prefix of the TF topics (a namespaced robot: "/robot1" gives
  /// /robot1/tf and /robot1/tf_static).
  std::string tf_namespace;
  /// Write rosbag2's metadata.yaml beside the file (the bag is a folder).
  bool metadata_yaml = true;
};

/// The frame of the colour camera in the bag.
inline constexpr const char* kCameraFrame = "camera_color_optical_frame";

/// Writes a bag of `frames` with intrinsics `k`. With metadata_yaml, `path`
/// is the bag folder (`<path>/<name>_0.mcap` or `.db3`), else the file.
void WriteTestBag(const std::filesystem::path& path,
                  const std::vector<BagFrame>& frames,
                  const CameraIntrinsics& k, const TestBagOptions& options);

/// Writes a ScanNet .sens file (version 4) of `frames`: depth zlib-
/// compressed in millimetres (shift 1000), colour as PNG (lossless) or JPEG,
/// optionally at `color_scale` times the depth size (ScanNet's colour is
/// larger). Frames listed in `invalid_poses` get ScanNet's -inf pose.
void WriteTestSens(const std::filesystem::path& path,
                   const std::vector<BagFrame>& frames,
                   const CameraIntrinsics& k, bool jpeg, int color_scale,
                   const std::vector<size_t>& invalid_poses = {});

}  // namespace semrec::io::testing
