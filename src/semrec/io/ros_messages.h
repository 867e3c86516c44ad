// The ROS 2 messages a recording of a camera carries, decoded from their
// serialized form (CDR, XCDR1 little or big endian with alignment, as
// rosbag2 stores them) by our own small decoder; no ROS is needed. Images
// are turned into semrec's: colour as RGB8, depth in metres.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "semrec/core/image.h"
#include "semrec/core/transform.h"

namespace semrec::io {

/// A message that cannot be decoded (truncated, wrong type, bad encoding
/// header). The bag reader adds the file, topic and message to the text.
class CdrError : public Error {
 public:
  using Error::Error;
};

struct RosHeader {
  int32_t stamp_sec = 0;
  uint32_t stamp_nanosec = 0;
  std::string frame_id;
  double StampSeconds() const { return stamp_sec + 1e-9 * stamp_nanosec; }
  int64_t StampNs() const {
    return int64_t{stamp_sec} * 1000000000 + stamp_nanosec;
  }
};

/// sensor_msgs/msg/Image.
struct RosImage {
  RosHeader header;
  uint32_t height = 0, width = 0;
  std::string encoding;
  uint8_t is_bigendian = 0;
  uint32_t step = 0;
  std::vector<uint8_t> data;
};

/// sensor_msgs/msg/CompressedImage.
struct RosCompressedImage {
  RosHeader header;
  std::string format;
  std::vector<uint8_t> data;
};

/// sensor_msgs/msg/CameraInfo (the fields semrec uses).
struct RosCameraInfo {
  RosHeader header;
  uint32_t height = 0, width = 0;
  std::string distortion_model;
  std::vector<double> d;
  std::array<double, 9> k{};
};

/// geometry_msgs/msg/TransformStamped: the pose of child_frame_id in
/// header.frame_id (T_parent_child).
struct RosTransform {
  RosHeader header;
  std::string child_frame_id;
  Transform T_parent_child;
};

/// A stamped pose from nav_msgs/msg/Odometry (of child_frame_id in
/// header.frame_id) or geometry_msgs/msg/PoseStamped (child_frame_id empty).
struct RosPose {
  RosHeader header;
  std::string child_frame_id;
  Transform T_parent_child;
};

RosImage DecodeRosImage(const uint8_t* data, size_t size);
RosCompressedImage DecodeRosCompressedImage(const uint8_t* data, size_t size);
RosCameraInfo DecodeRosCameraInfo(const uint8_t* data, size_t size);
/// tf2_msgs/msg/TFMessage.
std::vector<RosTransform> DecodeRosTfMessage(const uint8_t* data, size_t size);
RosPose DecodeRosOdometry(const uint8_t* data, size_t size);
RosPose DecodeRosPoseStamped(const uint8_t* data, size_t size);

/// The header of any message that starts with std_msgs/Header (all above but
/// TFMessage).
RosHeader DecodeRosHeader(const uint8_t* data, size_t size);

/// Colour from an Image (rgb8, bgr8, rgba8, bgra8, mono8) or a
/// CompressedImage (jpeg, png). Throws CdrError naming the encoding.
ColorImage RosColor(const RosImage& image);
ColorImage RosColor(const RosCompressedImage& image);
/// Depth in metres (0 = no measurement) from an Image (16UC1 / mono16 in
/// millimetres, 32FC1 in metres) or a CompressedImage (image_transport's
/// compressedDepth: a 12-byte header and a 16-bit PNG in millimetres, or a
/// plain 16-bit PNG).
DepthImage RosDepth(const RosImage& image);
DepthImage RosDepth(const RosCompressedImage& image);

/// The ros2msg schema text rosbag2 stores for `type` (the .msg text, then
/// each dependency after a line of 80 '=' and "MSG: pkg/Name"), for the
/// types above; empty for others.
std::string RosSchemaText(const std::string& type);

// Serialization, for tests and test bags (CDR little endian, as rosbag2
// writes on x86 and ARM).
std::vector<uint8_t> EncodeRosImage(const RosImage& m);
std::vector<uint8_t> EncodeRosCompressedImage(const RosCompressedImage& m);
std::vector<uint8_t> EncodeRosCameraInfo(const RosCameraInfo& m);
std::vector<uint8_t> EncodeRosTfMessage(const std::vector<RosTransform>& m);
std::vector<uint8_t> EncodeRosOdometry(const RosPose& m);
std::vector<uint8_t> EncodeRosPoseStamped(const RosPose& m);

}  // namespace semrec::io
