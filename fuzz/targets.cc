#include "fuzz/targets.h"

#include <unistd.h>

#include <cstdio>
#include <stdexcept>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/infer/model_registry.h"
#include "semrec/io/image_io.h"
#include "semrec/io/label_set_io.h"
#include "semrec/io/layouts.h"
#include "semrec/io/mcap_reader.h"
#include "semrec/io/mot_io.h"
#include "semrec/io/ply_io.h"
#include "semrec/io/pose_io.h"
#include "semrec/io/ros_messages.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/usd/usda_reader.h"

namespace fs = std::filesystem;

namespace semrec::fuzz {
namespace {

// Every reader of a format is tried even when an earlier one rejected the
// input.
struct Attempts {
  int accepted = 0;
  int rejected = 0;
  template <typename F>
  void operator()(F&& parse) {
    try {
      parse();
      ++accepted;
    } catch (const Error&) {
      ++rejected;
    }
  }
};

void ParseImage(const fs::path& path) {
  Attempts attempt;
  attempt([&] { io::ReadImageInfo(path); });
  attempt([&] { io::ReadColorImage(path); });
  attempt([&] { io::ReadDepthImage(path); });
  if (path.extension() == ".png") attempt([&] { io::ReadLabelImage(path); });
  // A colour JPEG is no depth map: accepted when some reader takes it.
  if (attempt.accepted == 0) throw Error("rejected");
}

void ParseIntrinsicsJson(const fs::path& path) {
  Attempts attempt;
  attempt([&] { io::ReadOpen3dIntrinsics(path); });
  attempt([&] { io::internal::ReadIntrinsicsFile(path, 640, 480); });
  if (attempt.rejected > 0) throw Error("rejected");
}

void ParseManifest(const fs::path& path) {
  // The manifest in its folder beside a small colour and depth image (what the
  // seeds' frames name): the layout detection runs as for a user's folder.
  const fs::path color = path.parent_path() / "color.png";
  if (!fs::exists(color)) {
    io::WritePng(color, ColorImage(8, 6, 3));
    io::WritePng(path.parent_path() / "depth.png", DepthImage16(8, 6, 1));
  }
  const io::SequenceReader reader =
      io::SequenceReader::Open(path.parent_path());
  if (reader.size() > 0) reader.Read(0);
}

// One ROS 2 message by its type name, images turned into semrec's too.
void DecodeRosMessage(const std::string& type, const uint8_t* data,
                      size_t size) {
  if (type == "sensor_msgs/msg/Image") {
    const io::RosImage m = io::DecodeRosImage(data, size);
    Attempts attempt;
    attempt([&] { io::RosColor(m); });
    attempt([&] { io::RosDepth(m); });
  } else if (type == "sensor_msgs/msg/CompressedImage") {
    const io::RosCompressedImage m = io::DecodeRosCompressedImage(data, size);
    Attempts attempt;
    attempt([&] { io::RosColor(m); });
    attempt([&] { io::RosDepth(m); });
  } else if (type == "sensor_msgs/msg/CameraInfo") {
    io::DecodeRosCameraInfo(data, size);
  } else if (type == "tf2_msgs/msg/TFMessage") {
    io::DecodeRosTfMessage(data, size);
  } else if (type == "nav_msgs/msg/Odometry") {
    io::DecodeRosOdometry(data, size);
  } else if (type == "geometry_msgs/msg/PoseStamped") {
    io::DecodeRosPoseStamped(data, size);
  }
}

// An MCAP file: every record and message, each message decoded by its
// schema, some read again by reference; then the file as a bag layout.
void ParseMcap(const fs::path& path) {
  {
    io::McapReader reader(path);
    std::vector<io::McapMessageRef> refs;
    reader.Scan(
        [&](const io::McapMessageInfo& info, const uint8_t* data, size_t size) {
          const auto& channel = reader.channels().at(info.channel_id);
          const auto schema = reader.schemas().find(channel.schema_id);
          if (schema != reader.schemas().end()) {
            Attempts attempt;
            attempt([&] { DecodeRosMessage(schema->second.name, data, size); });
          }
          if (refs.size() < 16) refs.push_back(info.ref);
        });
    for (const auto& ref : refs) reader.Read(ref);
  }
  const io::SequenceReader bag = io::SequenceReader::Open(path);
  bag.Read(0);
}

// A CDR message; the first byte picks its type.
void ParseCdr(const fs::path& path) {
  const std::vector<unsigned char> bytes = ReadFileBytes(path);
  if (bytes.empty()) throw Error("empty");
  static const char* kTypes[] = {
      "sensor_msgs/msg/Image",      "sensor_msgs/msg/CompressedImage",
      "sensor_msgs/msg/CameraInfo", "tf2_msgs/msg/TFMessage",
      "nav_msgs/msg/Odometry",      "geometry_msgs/msg/PoseStamped"};
  DecodeRosMessage(kTypes[bytes[0] % 6], bytes.data() + 1, bytes.size() - 1);
}

// A ScanNet .sens file: the index and the first and last frames.
void ParseSens(const fs::path& path) {
  const io::SequenceReader sens = io::SequenceReader::Open(path);
  sens.Read(0);
  sens.Read(sens.size() - 1);
}

const std::vector<Target> kTargets = {
    {"png", "PNG colour, depth and label images (libpng)", "image.png",
     ParseImage},
    {"jpeg", "JPEG colour images (OpenCV)", "image.jpg", ParseImage},
    {"pnm", "PGM/PPM depth and colour images (OpenCV)", "image.pgm",
     ParseImage},
    {"redwood_log", "Redwood/Open3D .log trajectories", "trajectory.log",
     [](const fs::path& p) { io::ReadRedwoodLog(p); }},
    {"pose_matrix", "7-Scenes/3DMatch frame-*.pose.txt 4x4 matrices",
     "frame-000000.pose.txt",
     [](const fs::path& p) { io::ReadPoseMatrixFile(p); }},
    {"tum", "TUM RGB-D groundtruth.txt trajectories", "groundtruth.txt",
     [](const fs::path& p) { io::ReadTumTrajectory(p); }},
    {"intrinsics_json", "Open3D PinholeCameraIntrinsic JSON", "intrinsics.json",
     ParseIntrinsicsJson},
    {"intrinsics_txt", "3x3 K matrix text (camera-intrinsics.txt)",
     "camera-intrinsics.txt",
     [](const fs::path& p) { io::ReadIntrinsicsMatrixFile(p, 640, 480); }},
    {"pose_correction", "--pose-correction YAML", "correction.yaml",
     [](const fs::path& p) { io::ReadPoseCorrection(p); }},
    {"manifest", "semrec sequence.yaml/.json manifests", "seq/sequence.yaml",
     ParseManifest},
    {"ply", "PLY point clouds and meshes (ascii and binary)", "cloud.ply",
     [](const fs::path& p) { io::ReadPly(p); }},
    {"usda", "USDA layers (semrec query, our reader)", "scene.usda",
     [](const fs::path& p) { usd::ReadScene(p); }},
    {"mot", "MOTChallenge det/gt text files", "det.txt",
     [](const fs::path& p) { io::ReadMotFile(p); }, /*empty_is_valid=*/true},
    {"label_set", "label set JSON files", "labels.json",
     [](const fs::path& p) { io::ReadLabelSetJson(p); }},
    {"model_registry", "model registry YAML (--registry)", "models.yaml",
     [](const fs::path& p) { infer::ModelRegistry::Load(p); }},
    {"mcap", "MCAP files (ROS 2 bags): records, chunks, messages, layout",
     "bag.mcap", ParseMcap},
    {"cdr", "ROS 2 CDR messages (first byte: the type)", "message.cdr",
     ParseCdr},
    {"sens", "ScanNet .sens files", "scene.sens", ParseSens},
};

// A private folder on a RAM disk where there is one: inputs are written and
// read back thousands of times a second.
const fs::path& ScratchDir() {
  static const fs::path dir = [] {
    const fs::path base = fs::is_directory("/dev/shm")
                              ? fs::path("/dev/shm")
                              : fs::temp_directory_path();
    fs::path d = base / ("semrec-fuzz-" + std::to_string(::getpid()));
    fs::create_directories(d);
    std::atexit([] {
      std::error_code ec;
      fs::remove_all(ScratchDir(), ec);
    });
    return d;
  }();
  return dir;
}

}  // namespace

const std::vector<Target>& Targets() { return kTargets; }

const Target& FindTarget(const std::string& name) {
  for (const Target& t : kTargets) {
    if (t.name == name) return t;
  }
  throw std::invalid_argument("no fuzz target '" + name + "'");
}

bool RunOne(const Target& target, const uint8_t* data, size_t size) {
  const fs::path path = ScratchDir() / target.file_name;
  fs::create_directories(path.parent_path());
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) throw std::runtime_error("cannot write " + path.string());
  const size_t written = size == 0 ? 0 : std::fwrite(data, 1, size, f);
  std::fclose(f);
  if (written != size) {
    throw std::runtime_error("short write to " + path.string());
  }
  try {
    target.parse(path);
    return true;
  } catch (const Error&) {
    return false;
  }
}

}  // namespace semrec::fuzz
