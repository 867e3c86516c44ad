#include "semrec/io/test_bags.h"

#include <sqlite3.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <memory>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "semrec/core/error.h"
#include "semrec/io/mcap_writer.h"
#include "semrec/io/ros_messages.h"

namespace fs = std::filesystem;

namespace semrec::io::testing {
namespace {

struct Message {
  std::string topic;
  int64_t time_ns;
  std::vector<uint8_t> data;
};

RosHeader Header(int64_t t_ns, const std::string& frame) {
  RosHeader h;
  h.stamp_sec = static_cast<int32_t>(t_ns / 1000000000);
  h.stamp_nanosec = static_cast<uint32_t>(t_ns % 1000000000);
  h.frame_id = frame;
  return h;
}

RosTransform Tf(int64_t t_ns, const std::string& parent,
                const std::string& child, const Transform& T) {
  return {Header(t_ns, parent), child, T};
}

// OpenCV's channel order, for its encoders.
cv::Mat ToBgr(const ColorImage& rgb) {
  cv::Mat bgr;
  cv::cvtColor(cv::Mat(rgb.height(), rgb.width(), CV_8UC3,
                       const_cast<uint8_t*>(rgb.data())),
               bgr, cv::COLOR_RGB2BGR);
  return bgr;
}

std::vector<uint8_t> Encode(const cv::Mat& img, const char* ext) {
  std::vector<uint8_t> out;
  cv::imencode(ext, img, out);
  return out;
}

std::vector<uint8_t> ColorMessage(const BagFrame& f, int64_t t,
                                  const TestBagOptions& o) {
  const RosHeader h = Header(t, kCameraFrame);
  if (o.compressed_color) {
    cv::Mat bgr = ToBgr(f.color);
    return EncodeRosCompressedImage(
        {h, "rgb8; jpeg compressed bgr8", Encode(bgr, ".jpg")});
  }
  RosImage m;
  m.header = h;
  m.width = static_cast<uint32_t>(f.color.width());
  m.height = static_cast<uint32_t>(f.color.height());
  m.encoding = o.bgr ? "bgr8" : "rgb8";
  m.step = m.width * 3;
  m.data = f.color.values();
  if (o.bgr) {
    for (size_t i = 0; i < m.data.size(); i += 3) {
      std::swap(m.data[i], m.data[i + 2]);
    }
  }
  return EncodeRosImage(m);
}

constexpr const char* kDepthFrame = "camera_depth_optical_frame";

std::vector<uint8_t> DepthMessage(const BagFrame& f, int64_t t,
                                  const TestBagOptions& o) {
  const RosHeader h =
      Header(t, o.depth_baseline_m > 0 ? kDepthFrame : kCameraFrame);
  DepthImage16 mm(f.depth_m.width(), f.depth_m.height());
  for (size_t p = 0; p < mm.values().size(); ++p) {
    mm.values()[p] = static_cast<uint16_t>(
        std::clamp(std::lround(f.depth_m.values()[p] * 1000.0f), 0L, 65535L));
  }
  if (o.compressed_depth) {
    const cv::Mat d(mm.height(), mm.width(), CV_16UC1, mm.data());
    std::vector<uint8_t> data(12, 0);  // format + 2 float quantisation params
    const std::vector<uint8_t> png = Encode(d, ".png");
    data.insert(data.end(), png.begin(), png.end());
    return EncodeRosCompressedImage(
        {h, "16UC1; compressedDepth png", std::move(data)});
  }
  RosImage m;
  m.header = h;
  m.width = static_cast<uint32_t>(mm.width());
  m.height = static_cast<uint32_t>(mm.height());
  m.encoding = o.float_depth ? "32FC1" : "16UC1";
  m.step = m.width * (o.float_depth ? 4 : 2);
  m.data.resize(size_t{m.step} * m.height);
  if (o.float_depth) {
    std::memcpy(m.data.data(), f.depth_m.data(), m.data.size());
  } else {
    std::memcpy(m.data.data(), mm.data(), m.data.size());
  }
  return EncodeRosImage(m);
}

// The chain's fixed parts and map -> odom's drift at time t (linear in t, so
// interpolation between its samples is exact).
const Transform& BaseCamera() {
  // base_link -> camera_link: 0.1 m ahead, 0.5 m up; camera_link -> optical:
  // ROS's optical convention (z forward, x right, y down).
  static const Transform T_base_link =
      Transform(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.1, 0, 0.5));
  return T_base_link;
}
Transform LinkOptical() {
  Eigen::Matrix3d R;
  R << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  return Transform(R, Eigen::Vector3d::Zero());
}
Transform MapOdom(double t_s) {
  return Transform(Eigen::Matrix3d::Identity(),
                   Eigen::Vector3d(0.02 * t_s, -0.01 * t_s, 0.0));
}

std::vector<Message> Messages(const std::vector<BagFrame>& frames,
                              const CameraIntrinsics& k,
                              const TestBagOptions& o) {
  std::vector<Message> out;
  const std::string color_topic = o.compressed_color
                                      ? "/camera/color/image_raw/compressed"
                                      : "/camera/color/image_raw";
  const std::string depth_ns = o.depth_baseline_m > 0
                                   ? "/camera/depth/"
                                   : "/camera/aligned_depth_to_color/";
  const std::string depth_topic =
      depth_ns +
      (o.compressed_depth ? "image_raw/compressedDepth" : "image_raw");
  const int64_t t0 = int64_t{1700000000} * 1000000000;
  auto ns = [&](double s) { return t0 + std::llround(s * 1e9); };
  if (o.tf) {
    out.push_back(
        {o.tf_namespace + "/tf_static", t0,
         EncodeRosTfMessage(
             {Tf(t0, "base_link", "camera_link", BaseCamera()),
              Tf(t0, "camera_link", kCameraFrame, LinkOptical()),
              Tf(t0, "camera_link", kDepthFrame,
                 Transform(LinkOptical().rotation(),
                           Eigen::Vector3d(0, -o.depth_baseline_m, 0)))})});
    // map -> odom every 40 ms over the whole recording and a bit beyond.
    const double end = frames.empty() ? 0.0 : frames.back().timestamp_s + 0.1;
    for (double t = frames.empty() ? 0.0 : frames.front().timestamp_s - 0.1;
         t <= end; t += 0.04) {
      out.push_back(
          {o.tf_namespace + "/tf", ns(t),
           EncodeRosTfMessage({Tf(ns(t), "map", "odom", MapOdom(t - 0.0))})});
    }
  }
  RosCameraInfo info;
  info.width = static_cast<uint32_t>(k.width);
  info.height = static_cast<uint32_t>(k.height);
  info.distortion_model = "plumb_bob";
  info.d = {0, 0, 0, 0, 0};
  info.k = {k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1};
  for (const BagFrame& f : frames) {
    const int64_t t = ns(f.timestamp_s);
    if (o.tf) {
      const Transform T_base_camera = BaseCamera() * LinkOptical();
      const Transform T_odom_base = MapOdom(f.timestamp_s).Inverse() *
                                    f.T_world_camera * T_base_camera.Inverse();
      out.push_back(
          {o.tf_namespace + "/tf", t,
           EncodeRosTfMessage({Tf(t, "odom", "base_link", T_odom_base)})});
    }
    if (o.odometry) {
      const Transform T_base_camera = BaseCamera() * LinkOptical();
      out.push_back(
          {"/odom", t,
           EncodeRosOdometry({Header(t, "map"), "base_link",
                              f.T_world_camera * T_base_camera.Inverse()})});
    }
    info.header = Header(t, kCameraFrame);
    out.push_back({"/camera/color/camera_info", t, EncodeRosCameraInfo(info)});
    out.push_back({color_topic, t, ColorMessage(f, t, o)});
    if (o.depth_baseline_m > 0) {
      RosCameraInfo depth_info = info;
      depth_info.header = Header(t, kDepthFrame);
      out.push_back(
          {depth_ns + "camera_info", t, EncodeRosCameraInfo(depth_info)});
    }
    if (o.depth) {
      const int64_t td = t + std::llround(o.depth_offset_ms * 1e6);
      out.push_back({depth_topic, td, DepthMessage(f, td, o)});
    }
  }
  std::stable_sort(
      out.begin(), out.end(),
      [](const Message& a, const Message& b) { return a.time_ns < b.time_ns; });
  return out;
}

std::string TypeOf(const std::string& topic) {
  if (topic.size() >= 3 && (topic.compare(topic.size() - 3, 3, "/tf") == 0 ||
                            topic.find("tf_static") != std::string::npos)) {
    return "tf2_msgs/msg/TFMessage";
  }
  if (topic == "/odom") return "nav_msgs/msg/Odometry";
  if (topic.find("camera_info") != std::string::npos) {
    return "sensor_msgs/msg/CameraInfo";
  }
  if (topic.find("compressed") != std::string::npos) {
    return "sensor_msgs/msg/CompressedImage";
  }
  return "sensor_msgs/msg/Image";
}

void WriteMcap(const fs::path& file, const std::vector<Message>& messages,
               const TestBagOptions& o) {
  McapWriterOptions w;
  w.compression = o.compression;
  w.crc = o.chunk_crc;
  w.chunk_bytes = 256 * 1024;
  McapWriter writer(file, w);
  std::map<std::string, uint16_t> channels;
  for (const Message& m : messages) {
    if (!channels.count(m.topic)) {
      const std::string type = TypeOf(m.topic);
      channels[m.topic] = writer.AddChannel(
          writer.AddSchema(type, "ros2msg", RosSchemaText(type)), m.topic);
    }
  }
  for (const Message& m : messages) {
    writer.Write(channels.at(m.topic), static_cast<uint64_t>(m.time_ns),
                 m.data);
  }
  writer.AddMetadata("rosbag2", {{"serialized_metadata", ""}});
  writer.Close();
}

void Exec(sqlite3* db, const std::string& sql) {
  char* error = nullptr;
  if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &error) != SQLITE_OK) {
    const std::string text = error ? error : "?";
    sqlite3_free(error);
    throw Error("sqlite: " + text);
  }
}

void WriteSqlite(const fs::path& file, const std::vector<Message>& messages) {
  fs::remove(file);
  sqlite3* raw = nullptr;
  if (sqlite3_open(file.c_str(), &raw) != SQLITE_OK) {
    sqlite3_close(raw);
    throw IoError(file, "cannot create the SQLite bag");
  }
  std::unique_ptr<sqlite3, decltype(&sqlite3_close)> db(raw, &sqlite3_close);
  // rosbag2's schema (version 4, Iron).
  Exec(db.get(),
       "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro "
       "TEXT NOT NULL); INSERT INTO schema VALUES (4, 'iron');"
       "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type "
       "TEXT NOT NULL, serialization_format TEXT NOT NULL, "
       "offered_qos_profiles TEXT NOT NULL, type_description_hash TEXT NOT "
       "NULL);"
       "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT "
       "NULL, timestamp INTEGER NOT NULL, data BLOB NOT NULL);"
       "BEGIN;");
  std::map<std::string, int> ids;
  for (const Message& m : messages) {
    if (ids.count(m.topic)) continue;
    const int id = static_cast<int>(ids.size()) + 1;
    ids[m.topic] = id;
    Exec(db.get(), fmt::format("INSERT INTO topics VALUES ({}, '{}', '{}', "
                               "'cdr', '', '')",
                               id, m.topic, TypeOf(m.topic)));
  }
  sqlite3_stmt* raw_stmt = nullptr;
  sqlite3_prepare_v2(db.get(),
                     "INSERT INTO messages(topic_id, timestamp, data) VALUES "
                     "(?, ?, ?)",
                     -1, &raw_stmt, nullptr);
  std::unique_ptr<sqlite3_stmt, decltype(&sqlite3_finalize)> stmt(
      raw_stmt, &sqlite3_finalize);
  for (const Message& m : messages) {
    sqlite3_bind_int(stmt.get(), 1, ids.at(m.topic));
    sqlite3_bind_int64(stmt.get(), 2, m.time_ns);
    sqlite3_bind_blob(stmt.get(), 3, m.data.data(),
                      static_cast<int>(m.data.size()), SQLITE_STATIC);
    if (sqlite3_step(stmt.get()) != SQLITE_DONE) {
      throw IoError(file, "cannot insert a message");
    }
    sqlite3_reset(stmt.get());
  }
  Exec(db.get(), "COMMIT;");
}

void WriteMetadata(const fs::path& folder, const std::string& file,
                   const std::vector<Message>& messages,
                   const TestBagOptions& o) {
  std::map<std::string, size_t> counts;
  for (const Message& m : messages) ++counts[m.topic];
  std::string y = fmt::format(
      "rosbag2_bagfile_information:\n  version: 8\n  storage_identifier: "
      "{}\n  relative_file_paths:\n    - {}\n  message_count: {}\n  "
      "topics_with_message_count:\n",
      o.storage, file, messages.size());
  for (const auto& [topic, n] : counts) {
    y += fmt::format(
        "    - topic_metadata:\n        name: {}\n        type: {}\n        "
        "serialization_format: cdr\n      message_count: {}\n",
        topic, TypeOf(topic), n);
  }
  std::ofstream(folder / "metadata.yaml") << y;
}

}  // namespace

void WriteTestBag(const fs::path& path, const std::vector<BagFrame>& frames,
                  const CameraIntrinsics& k, const TestBagOptions& options) {
  const std::vector<Message> messages = Messages(frames, k, options);
  const std::string ext = options.storage == "sqlite3" ? ".db3" : ".mcap";
  fs::path file = path;
  if (options.metadata_yaml) {
    fs::create_directories(path);
    file = path / (path.filename().string() + "_0" + ext);
    WriteMetadata(path, file.filename().string(), messages, options);
  }
  if (options.storage == "sqlite3") {
    WriteSqlite(file, messages);
  } else {
    WriteMcap(file, messages, options);
  }
}

void WriteTestSens(const fs::path& path, const std::vector<BagFrame>& frames,
                   const CameraIntrinsics& k, bool jpeg, int color_scale,
                   const std::vector<size_t>& invalid_poses) {
  std::vector<uint8_t> out;
  auto put = [&](const void* p, size_t n) {
    const auto* b = static_cast<const uint8_t*>(p);
    out.insert(out.end(), b, b + n);
  };
  auto put_u32 = [&](uint32_t v) { put(&v, 4); };
  auto put_u64 = [&](uint64_t v) { put(&v, 8); };
  auto put_matrix = [&](const Eigen::Matrix4d& m) {
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) {
        const auto v = static_cast<float>(m(r, c));
        put(&v, 4);
      }
    }
  };
  Eigen::Matrix4d K = Eigen::Matrix4d::Identity();
  K(0, 0) = k.fx;
  K(1, 1) = k.fy;
  K(0, 2) = k.cx;
  K(1, 2) = k.cy;
  Eigen::Matrix4d Kc = K;
  Kc.topRows(2) *= color_scale;
  put_u32(4);
  const std::string sensor = "StructureSensor";
  put_u64(sensor.size());
  put(sensor.data(), sensor.size());
  put_matrix(Kc);
  put_matrix(Eigen::Matrix4d::Identity());
  put_matrix(K);
  put_matrix(Eigen::Matrix4d::Identity());
  const int32_t color_type = jpeg ? 2 : 1, depth_type = 1;
  put(&color_type, 4);
  put(&depth_type, 4);
  put_u32(static_cast<uint32_t>(k.width * color_scale));
  put_u32(static_cast<uint32_t>(k.height * color_scale));
  put_u32(static_cast<uint32_t>(k.width));
  put_u32(static_cast<uint32_t>(k.height));
  const float shift = 1000.0f;
  put(&shift, 4);
  put_u64(frames.size());
  for (size_t i = 0; i < frames.size(); ++i) {
    const BagFrame& f = frames[i];
    Eigen::Matrix4d pose = f.T_world_camera.Matrix();
    if (std::find(invalid_poses.begin(), invalid_poses.end(), i) !=
        invalid_poses.end()) {
      pose.setConstant(-std::numeric_limits<double>::infinity());
    }
    put_matrix(pose);
    put_u64(static_cast<uint64_t>(std::llround(f.timestamp_s * 1e6)));
    put_u64(static_cast<uint64_t>(std::llround(f.timestamp_s * 1e6)));
    cv::Mat bgr = ToBgr(f.color);
    if (color_scale != 1) {
      cv::resize(bgr, bgr, cv::Size(), color_scale, color_scale,
                 cv::INTER_NEAREST);
    }
    const std::vector<uint8_t> color = Encode(bgr, jpeg ? ".jpg" : ".png");
    std::vector<uint16_t> mm(f.depth_m.values().size());
    for (size_t p = 0; p < mm.size(); ++p) {
      mm[p] = static_cast<uint16_t>(std::lround(f.depth_m.values()[p] * 1000));
    }
    uLongf n = compressBound(static_cast<uLong>(mm.size() * 2));
    std::vector<uint8_t> depth(n);
    compress(depth.data(), &n, reinterpret_cast<const Bytef*>(mm.data()),
             static_cast<uLong>(mm.size() * 2));
    depth.resize(n);
    put_u64(color.size());
    put_u64(depth.size());
    put(color.data(), color.size());
    put(depth.data(), depth.size());
  }
  put_u64(0);  // no IMU frames
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(out.data()),
             static_cast<std::streamsize>(out.size()));
}

}  // namespace semrec::io::testing
