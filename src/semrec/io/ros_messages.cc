#include "semrec/io/ros_messages.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <fmt/format.h>

#include "semrec/io/image_io.h"

namespace semrec::io {
namespace {

// XCDR1 reader: a 4-byte encapsulation header (0x00 0x00 big endian,
// 0x00 0x01 little endian), then primitives aligned to their size counted
// from the end of the header.
class CdrReader {
 public:
  CdrReader(const uint8_t* data, size_t size, const char* type) : type_(type) {
    if (size < 4 || data[0] != 0) {
      throw CdrError(
          fmt::format("{}: not CDR (bad encapsulation header)", type_));
    }
    if (data[1] > 1) {
      throw CdrError(fmt::format(
          "{}: encapsulation {} is not plain CDR (XCDR2 is not read)", type_,
          data[1]));
    }
    little_ = data[1] == 1;
    data_ = data + 4;
    size_ = size - 4;
  }

  template <typename T>
  T Get() {
    Align(sizeof(T));
    Need(sizeof(T));
    uint8_t bytes[sizeof(T)];
    std::memcpy(bytes, data_ + pos_, sizeof(T));
    if (!little_) std::reverse(bytes, bytes + sizeof(T));
    pos_ += sizeof(T);
    T v;
    std::memcpy(&v, bytes, sizeof(T));
    return v;
  }
  std::string String() {
    const uint32_t n = Get<uint32_t>();
    Need(n);
    if (n == 0) return {};
    // The length counts the terminating NUL.
    std::string s(reinterpret_cast<const char*>(data_ + pos_), n - 1);
    pos_ += n;
    return s;
  }
  std::vector<uint8_t> Bytes() {
    const uint32_t n = Get<uint32_t>();
    Need(n);
    std::vector<uint8_t> out(data_ + pos_, data_ + pos_ + n);
    pos_ += n;
    return out;
  }
  std::vector<double> Doubles() {
    const uint32_t n = Get<uint32_t>();
    Need(uint64_t{n} * 8);
    std::vector<double> out(n);
    for (double& v : out) v = Get<double>();
    return out;
  }
  uint32_t Count(size_t min_element_bytes) {
    const uint32_t n = Get<uint32_t>();
    Need(uint64_t{n} * min_element_bytes);
    return n;
  }
  RosHeader Header() {
    RosHeader h;
    h.stamp_sec = Get<int32_t>();
    h.stamp_nanosec = Get<uint32_t>();
    h.frame_id = String();
    return h;
  }
  Transform Pose() {
    // Point/Vector3 then Quaternion (x, y, z, w).
    Eigen::Vector3d t;
    for (int i = 0; i < 3; ++i) t[i] = Get<double>();
    double q[4];
    for (double& v : q) v = Get<double>();
    const Eigen::Quaterniond quat(q[3], q[0], q[1], q[2]);
    if (!t.allFinite() || !quat.coeffs().allFinite() || quat.norm() < 1e-6) {
      throw CdrError(
          fmt::format("{}: a pose with a non-finite or zero "
                      "rotation",
                      type_));
    }
    return Transform::FromQuaternion(quat, t);
  }
  void Skip(size_t n) {
    Need(n);
    pos_ += n;
  }

 private:
  void Align(size_t n) {
    const size_t pad = (n - pos_ % n) % n;
    Need(pad);
    pos_ += pad;
  }
  void Need(uint64_t n) const {
    if (n > size_ - pos_) {
      throw CdrError(
          fmt::format("{}: message ends early (needs {} more "
                      "bytes at offset {}, has {})",
                      type_, n, pos_ + 4, size_ - pos_));
    }
  }

  const char* type_;
  const uint8_t* data_ = nullptr;
  size_t size_ = 0;
  size_t pos_ = 0;
  bool little_ = true;
};

class CdrWriter {
 public:
  CdrWriter() { out_ = {0x00, 0x01, 0x00, 0x00}; }
  template <typename T>
  void Put(T v) {
    while ((out_.size() - 4) % sizeof(T) != 0) out_.push_back(0);
    const size_t at = out_.size();
    out_.resize(at + sizeof(T));
    std::memcpy(out_.data() + at, &v, sizeof(T));
  }
  void String(const std::string& s) {
    Put<uint32_t>(static_cast<uint32_t>(s.size() + 1));
    out_.insert(out_.end(), s.begin(), s.end());
    out_.push_back(0);
  }
  void Bytes(const std::vector<uint8_t>& b) {
    Put<uint32_t>(static_cast<uint32_t>(b.size()));
    out_.insert(out_.end(), b.begin(), b.end());
  }
  void Header(const RosHeader& h) {
    Put<int32_t>(h.stamp_sec);
    Put<uint32_t>(h.stamp_nanosec);
    String(h.frame_id);
  }
  void Pose(const Transform& T) {
    for (int i = 0; i < 3; ++i) Put<double>(T.translation()[i]);
    const Eigen::Quaterniond q = T.Quaternion();
    Put<double>(q.x());
    Put<double>(q.y());
    Put<double>(q.z());
    Put<double>(q.w());
  }
  std::vector<uint8_t> Take() { return std::move(out_); }

 private:
  std::vector<uint8_t> out_;
};

// Images inside messages: the file readers' checks; their FormatError
// becomes a CdrError (the bag reader names the file and message).
template <typename F>
auto Decoded(const std::string& what, F&& decode) {
  try {
    return decode();
  } catch (const FormatError& e) {
    throw CdrError(what + ": " + e.what());
  }
}

void CheckImage(const RosImage& m, int bytes_per_pixel) {
  if (m.width == 0 || m.height == 0 || m.width > 1 << 15 ||
      m.height > 1 << 15) {
    throw CdrError(
        fmt::format("Image: size {}x{} is not usable", m.width, m.height));
  }
  const uint64_t row = uint64_t{m.width} * bytes_per_pixel;
  if (m.step < row || uint64_t{m.step} * m.height > m.data.size()) {
    throw CdrError(fmt::format(
        "Image ({}): step {} and {} rows need {} bytes, the message has {}",
        m.encoding, m.step, m.height, uint64_t{m.step} * m.height,
        m.data.size()));
  }
}

template <typename T>
T Sample(const RosImage& m, size_t at) {
  uint8_t b[sizeof(T)];
  std::memcpy(b, m.data.data() + at, sizeof(T));
  if (m.is_bigendian) std::reverse(b, b + sizeof(T));
  T v;
  std::memcpy(&v, b, sizeof(T));
  return v;
}

}  // namespace

RosHeader DecodeRosHeader(const uint8_t* data, size_t size) {
  return CdrReader(data, size, "Header").Header();
}

RosImage DecodeRosImage(const uint8_t* data, size_t size) {
  CdrReader r(data, size, "sensor_msgs/msg/Image");
  RosImage m;
  m.header = r.Header();
  m.height = r.Get<uint32_t>();
  m.width = r.Get<uint32_t>();
  m.encoding = r.String();
  m.is_bigendian = r.Get<uint8_t>();
  m.step = r.Get<uint32_t>();
  m.data = r.Bytes();
  return m;
}

RosCompressedImage DecodeRosCompressedImage(const uint8_t* data, size_t size) {
  CdrReader r(data, size, "sensor_msgs/msg/CompressedImage");
  RosCompressedImage m;
  m.header = r.Header();
  m.format = r.String();
  m.data = r.Bytes();
  return m;
}

RosCameraInfo DecodeRosCameraInfo(const uint8_t* data, size_t size) {
  CdrReader r(data, size, "sensor_msgs/msg/CameraInfo");
  RosCameraInfo m;
  m.header = r.Header();
  m.height = r.Get<uint32_t>();
  m.width = r.Get<uint32_t>();
  m.distortion_model = r.String();
  m.d = r.Doubles();
  for (double& v : m.k) v = r.Get<double>();
  return m;  // r, p, binning and roi are not used
}

std::vector<RosTransform> DecodeRosTfMessage(const uint8_t* data, size_t size) {
  CdrReader r(data, size, "tf2_msgs/msg/TFMessage");
  // A transform is at least a header (12 bytes) + child (4) + 56 bytes.
  const uint32_t n = r.Count(72);
  std::vector<RosTransform> out(n);
  for (RosTransform& t : out) {
    t.header = r.Header();
    t.child_frame_id = r.String();
    t.T_parent_child = r.Pose();
  }
  return out;
}

RosPose DecodeRosOdometry(const uint8_t* data, size_t size) {
  CdrReader r(data, size, "nav_msgs/msg/Odometry");
  RosPose m;
  m.header = r.Header();
  m.child_frame_id = r.String();
  m.T_parent_child = r.Pose();
  return m;  // covariance and twist are not used
}

RosPose DecodeRosPoseStamped(const uint8_t* data, size_t size) {
  CdrReader r(data, size, "geometry_msgs/msg/PoseStamped");
  RosPose m;
  m.header = r.Header();
  m.T_parent_child = r.Pose();
  return m;
}

ColorImage RosColor(const RosImage& m) {
  int channels = 0;
  bool bgr = false;
  if (m.encoding == "rgb8") {
    channels = 3;
  } else if (m.encoding == "bgr8") {
    channels = 3;
    bgr = true;
  } else if (m.encoding == "rgba8") {
    channels = 4;
  } else if (m.encoding == "bgra8") {
    channels = 4;
    bgr = true;
  } else if (m.encoding == "mono8") {
    channels = 1;
  } else {
    throw CdrError(fmt::format(
        "Image: colour encoding '{}' is not read (rgb8, bgr8, rgba8, bgra8 "
        "and mono8 are)",
        m.encoding));
  }
  CheckImage(m, channels);
  ColorImage out(static_cast<int>(m.width), static_cast<int>(m.height), 3);
  for (uint32_t y = 0; y < m.height; ++y) {
    const uint8_t* row = m.data.data() + size_t{y} * m.step;
    for (uint32_t x = 0; x < m.width; ++x) {
      const uint8_t* p = row + size_t{x} * channels;
      for (int c = 0; c < 3; ++c) {
        const int src = channels == 1 ? 0 : (bgr ? 2 - c : c);
        out(static_cast<int>(x), static_cast<int>(y), c) = p[src];
      }
    }
  }
  return out;
}

ColorImage RosColor(const RosCompressedImage& m) {
  const std::string what = "CompressedImage (" + m.format + ")";
  return Decoded(what, [&] { return DecodeColorImage(m.data, "message"); });
}

DepthImage RosDepth(const RosImage& m) {
  const bool mm = m.encoding == "16UC1" || m.encoding == "mono16";
  const bool metres = m.encoding == "32FC1";
  if (!mm && !metres) {
    throw CdrError(fmt::format(
        "Image: depth encoding '{}' is not read (16UC1 in millimetres and "
        "32FC1 in metres are)",
        m.encoding));
  }
  CheckImage(m, mm ? 2 : 4);
  const int w = static_cast<int>(m.width), h = static_cast<int>(m.height);
  if (mm) {
    DepthImage16 raw(w, h);
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        raw(x, y) =
            Sample<uint16_t>(m, size_t{static_cast<size_t>(y)} * m.step +
                                    size_t{static_cast<size_t>(x)} * 2);
      }
    }
    return DepthToMeters(raw, 1000.0);
  }
  DepthImage out(w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      float d = Sample<float>(m, size_t{static_cast<size_t>(y)} * m.step +
                                     size_t{static_cast<size_t>(x)} * 4);
      if (!std::isfinite(d) || d < 0.0f) d = 0.0f;
      out(x, y) = d;
    }
  }
  return out;
}

DepthImage RosDepth(const RosCompressedImage& m) {
  const std::string what = "CompressedImage (" + m.format + ")";
  const bool depth_transport =
      m.format.find("compressedDepth") != std::string::npos;
  // Older image_transport names no codec: PNG then; RVL is not read.
  if (depth_transport && m.format.find("rvl") != std::string::npos) {
    throw CdrError(what + ": RVL compressedDepth is not read (PNG is)");
  }
  // image_transport's compressedDepth: int32 format + two float32
  // quantisation parameters before the PNG (used for 32FC1 only).
  const size_t skip = depth_transport ? 12 : 0;
  if (m.data.size() <= skip) throw CdrError(what + ": no image data");
  const std::vector<uint8_t> png(m.data.begin() + skip, m.data.end());
  const DepthImage16 raw =
      Decoded(what, [&] { return DecodeDepthImage(png, "message"); });
  if (!depth_transport || m.format.rfind("32FC1", 0) != 0) {
    return DepthToMeters(raw, 1000.0);  // 16UC1: millimetres
  }
  // 32FC1: inverse depth quantised as depth = a / (value - b), 0 = none.
  float a = 0, b = 0;
  std::memcpy(&a, m.data.data() + 4, 4);
  std::memcpy(&b, m.data.data() + 8, 4);
  DepthImage out(raw.width(), raw.height());
  for (size_t p = 0; p < raw.values().size(); ++p) {
    const float v = raw.values()[p];
    const float d = v == 0.0f ? 0.0f : a / (v - b);
    out.values()[p] = std::isfinite(d) && d > 0.0f ? d : 0.0f;
  }
  return out;
}

namespace {

const char* kTimeMsg = "int32 sec\nuint32 nanosec\n";
const char* kHeaderMsg = "builtin_interfaces/Time stamp\nstring frame_id\n";
const char* kVector3Msg = "float64 x\nfloat64 y\nfloat64 z\n";
const char* kPointMsg = "float64 x\nfloat64 y\nfloat64 z\n";
const char* kQuaternionMsg =
    "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n";
const char* kPoseMsg = "Point position\nQuaternion orientation\n";

std::string WithDependencies(
    const std::string& main,
    const std::vector<std::pair<std::string, std::string>>& deps) {
  std::string text = main;
  for (const auto& [name, body] : deps) {
    text += std::string(80, '=') + "\nMSG: " + name + "\n" + body;
  }
  return text;
}

}  // namespace

std::string RosSchemaText(const std::string& type) {
  const std::pair<std::string, std::string> time = {"builtin_interfaces/Time",
                                                    kTimeMsg};
  const std::pair<std::string, std::string> header = {"std_msgs/Header",
                                                      kHeaderMsg};
  const std::pair<std::string, std::string> pose = {"geometry_msgs/Pose",
                                                    kPoseMsg};
  const std::pair<std::string, std::string> point = {"geometry_msgs/Point",
                                                     kPointMsg};
  const std::pair<std::string, std::string> quaternion = {
      "geometry_msgs/Quaternion", kQuaternionMsg};
  if (type == "sensor_msgs/msg/Image") {
    return WithDependencies(
        "std_msgs/Header header\nuint32 height\nuint32 width\nstring "
        "encoding\nuint8 is_bigendian\nuint32 step\nuint8[] data\n",
        {header, time});
  }
  if (type == "sensor_msgs/msg/CompressedImage") {
    return WithDependencies(
        "std_msgs/Header header\nstring format\nuint8[] data\n",
        {header, time});
  }
  if (type == "sensor_msgs/msg/CameraInfo") {
    return WithDependencies(
        "std_msgs/Header header\nuint32 height\nuint32 width\nstring "
        "distortion_model\nfloat64[] d\nfloat64[9] k\nfloat64[9] "
        "r\nfloat64[12] p\nuint32 binning_x\nuint32 binning_y\n"
        "RegionOfInterest roi\n",
        {header,
         time,
         {"sensor_msgs/RegionOfInterest",
          "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 "
          "width\nbool do_rectify\n"}});
  }
  if (type == "tf2_msgs/msg/TFMessage") {
    return WithDependencies(
        "geometry_msgs/TransformStamped[] transforms\n",
        {{"geometry_msgs/TransformStamped",
          "std_msgs/Header header\nstring child_frame_id\nTransform "
          "transform\n"},
         header,
         time,
         {"geometry_msgs/Transform",
          "Vector3 translation\nQuaternion rotation\n"},
         {"geometry_msgs/Vector3", kVector3Msg},
         quaternion});
  }
  if (type == "nav_msgs/msg/Odometry") {
    return WithDependencies(
        "std_msgs/Header header\nstring child_frame_id\n"
        "geometry_msgs/PoseWithCovariance pose\n"
        "geometry_msgs/TwistWithCovariance twist\n",
        {header,
         time,
         {"geometry_msgs/PoseWithCovariance",
          "Pose pose\nfloat64[36] covariance\n"},
         pose,
         point,
         quaternion,
         {"geometry_msgs/TwistWithCovariance",
          "Twist twist\nfloat64[36] covariance\n"},
         {"geometry_msgs/Twist", "Vector3 linear\nVector3 angular\n"},
         {"geometry_msgs/Vector3", kVector3Msg}});
  }
  if (type == "geometry_msgs/msg/PoseStamped") {
    return WithDependencies("std_msgs/Header header\nPose pose\n",
                            {header, time, pose, point, quaternion});
  }
  return {};
}

std::vector<uint8_t> EncodeRosImage(const RosImage& m) {
  CdrWriter w;
  w.Header(m.header);
  w.Put<uint32_t>(m.height);
  w.Put<uint32_t>(m.width);
  w.String(m.encoding);
  w.Put<uint8_t>(m.is_bigendian);
  w.Put<uint32_t>(m.step);
  w.Bytes(m.data);
  return w.Take();
}

std::vector<uint8_t> EncodeRosCompressedImage(const RosCompressedImage& m) {
  CdrWriter w;
  w.Header(m.header);
  w.String(m.format);
  w.Bytes(m.data);
  return w.Take();
}

std::vector<uint8_t> EncodeRosCameraInfo(const RosCameraInfo& m) {
  CdrWriter w;
  w.Header(m.header);
  w.Put<uint32_t>(m.height);
  w.Put<uint32_t>(m.width);
  w.String(m.distortion_model);
  w.Put<uint32_t>(static_cast<uint32_t>(m.d.size()));
  for (double v : m.d) w.Put<double>(v);
  for (double v : m.k) w.Put<double>(v);
  const double r[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (double v : r) w.Put<double>(v);
  const double p[12] = {m.k[0], m.k[1], m.k[2], 0,      m.k[3], m.k[4],
                        m.k[5], 0,      m.k[6], m.k[7], m.k[8], 0};
  for (double v : p) w.Put<double>(v);
  w.Put<uint32_t>(0);  // binning
  w.Put<uint32_t>(0);
  for (int i = 0; i < 4; ++i) w.Put<uint32_t>(0);  // roi
  w.Put<uint8_t>(0);
  return w.Take();
}

std::vector<uint8_t> EncodeRosTfMessage(const std::vector<RosTransform>& m) {
  CdrWriter w;
  w.Put<uint32_t>(static_cast<uint32_t>(m.size()));
  for (const RosTransform& t : m) {
    w.Header(t.header);
    w.String(t.child_frame_id);
    w.Pose(t.T_parent_child);
  }
  return w.Take();
}

std::vector<uint8_t> EncodeRosOdometry(const RosPose& m) {
  CdrWriter w;
  w.Header(m.header);
  w.String(m.child_frame_id);
  w.Pose(m.T_parent_child);
  for (int i = 0; i < 36; ++i) w.Put<double>(0.0);      // pose covariance
  for (int i = 0; i < 6 + 36; ++i) w.Put<double>(0.0);  // twist
  return w.Take();
}

std::vector<uint8_t> EncodeRosPoseStamped(const RosPose& m) {
  CdrWriter w;
  w.Header(m.header);
  w.Pose(m.T_parent_child);
  return w.Take();
}

}  // namespace semrec::io
