// One RGB-D observation: colour, metric depth, camera pose and time.
#pragma once

#include <cstddef>
#include <filesystem>

#include "semrec/core/camera.h"
#include "semrec/core/image.h"
#include "semrec/core/transform.h"

namespace semrec {

struct Frame {
  /// Position in the sequence (0-based, after any stride / selection).
  size_t index = 0;
  /// Capture time in seconds (the dataset's clock; frame index / nominal rate
  /// when unknown).
  double timestamp_s = 0.0;
  /// RGB, 3 channels, same size as depth.
  ColorImage color;
  /// Metric depth in metres, 0 = invalid.
  DepthImage depth;
  /// Maps camera-frame points into the world frame.
  Transform T_world_camera;
  CameraIntrinsics intrinsics;
  /// Source files, for messages.
  std::filesystem::path color_path;
  std::filesystem::path depth_path;
};

}  // namespace semrec
