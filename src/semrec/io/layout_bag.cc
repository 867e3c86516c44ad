// ROS 2 bags as a sequence layout: colour and depth images paired by header
// stamp, intrinsics from CameraInfo, the camera's pose from the TF tree (or a
// pose topic) interpolated at the colour stamp. Depth in its own optical
// frame is registered into the colour camera. One scan indexes the bag;
// frames are decoded on demand (BagFrames).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <mutex>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include "semrec/core/error.h"
#include "semrec/core/progress.h"
#include "semrec/io/bag_storage.h"
#include "semrec/io/layouts.h"
#include "semrec/io/ros_messages.h"
#include "semrec/io/tf_tree.h"

namespace fs = std::filesystem;

namespace semrec::io::internal {
namespace {

constexpr const char* kImage = "sensor_msgs/msg/Image";
constexpr const char* kCompressed = "sensor_msgs/msg/CompressedImage";
constexpr const char* kCameraInfo = "sensor_msgs/msg/CameraInfo";
constexpr const char* kTf = "tf2_msgs/msg/TFMessage";
constexpr const char* kOdometry = "nav_msgs/msg/Odometry";
constexpr const char* kPoseStamped = "geometry_msgs/msg/PoseStamped";

struct Stamped {
  int64_t stamp_ns = 0;
  BagMessageRef ref;
};

struct TopicData {
  std::string type;
  size_t count = 0;
  int64_t first_ns = 0, last_ns = 0;
  std::string frame_id;             // of the first message with a header
  std::vector<Stamped> messages;    // images
  std::vector<RosCameraInfo> info;  // the first CameraInfo
  std::vector<RosPose> poses;       // Odometry / PoseStamped
};

bool IsImage(const TopicData& t) {
  return t.type == kImage || t.type == kCompressed;
}

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return s;
}

bool Contains(const std::string& s, const char* part) {
  return Lower(s).find(part) != std::string::npos;
}

// Everything one scan of the bag collects.
struct BagScan {
  std::map<std::string, TopicData> topics;
  TfTree tf;
  size_t undecodable = 0;
};

BagScan ScanBag(BagStorage* bag) {
  BagScan scan;
  // Progress in percent of the bag (bytes of MCAP, messages of SQLite): a
  // long recording takes a while to index.
  const uint64_t extent = std::max<uint64_t>(1, bag->Extent());
  Progress progress("indexing bag", 100);
  size_t percent = 0;
  bag->Scan([&](const BagMessage& m) {
    const auto now = static_cast<size_t>(std::min<uint64_t>(
        100, static_cast<uint64_t>(100.0 * static_cast<double>(m.done) /
                                   static_cast<double>(extent))));
    if (now > percent) progress.Tick(now - percent), percent = now;
    TopicData& t = scan.topics[*m.topic];
    if (t.count == 0) {
      t.type = *m.type;
      t.first_ns = m.log_time_ns;
    }
    ++t.count;
    t.last_ns = m.log_time_ns;
    try {
      if (t.type == kTf) {
        // /tf_static, also namespaced (/robot1/tf_static).
        const std::string& topic = *m.topic;
        const bool is_static =
            topic.size() >= 9 &&
            topic.compare(topic.size() - 9, 9, "tf_static") == 0;
        for (const RosTransform& x : DecodeRosTfMessage(m.data, m.size)) {
          scan.tf.Add(x, is_static);
        }
      } else if (IsImage(t)) {
        const RosHeader h = DecodeRosHeader(m.data, m.size);
        if (t.frame_id.empty()) t.frame_id = h.frame_id;
        t.messages.push_back({h.StampNs(), m.ref});
      } else if (t.type == kCameraInfo && t.info.empty()) {
        t.info.push_back(DecodeRosCameraInfo(m.data, m.size));
        t.frame_id = t.info[0].header.frame_id;
      } else if (t.type == kOdometry || t.type == kPoseStamped) {
        t.poses.push_back(t.type == kOdometry
                              ? DecodeRosOdometry(m.data, m.size)
                              : DecodeRosPoseStamped(m.data, m.size));
      }
    } catch (const CdrError& e) {
      if (scan.undecodable++ == 0) {
        spdlog::warn(
            "{}: a {} message on {} cannot be decoded ({}); such "
            "messages are skipped",
            bag->File(m.ref).string(), t.type, *m.topic, e.what());
      }
    }
  });
  if (percent < 100) progress.Tick(100 - percent);
  return scan;
}

// The topic given, or the best-scoring candidate (ties: more messages).
std::string PickTopic(
    const BagScan& scan, const std::string& given,
    const std::function<int(const std::string&, const TopicData&)>& score,
    const fs::path& path, const std::string& what) {
  if (!given.empty()) {
    if (!scan.topics.count(given)) {
      throw FormatError(
          path, fmt::format("no topic '{}' in the bag (for {})", given, what));
    }
    if (score(given, scan.topics.at(given)) < 0) {
      throw FormatError(path,
                        fmt::format("topic '{}' ({}) cannot be the {}", given,
                                    scan.topics.at(given).type, what));
    }
    return given;
  }
  std::string best;
  int best_score = -1;
  size_t best_count = 0;
  for (const auto& [name, t] : scan.topics) {
    const int s = score(name, t);
    if (s > best_score || (s == best_score && s >= 0 && t.count > best_count)) {
      best = name;
      best_score = s;
      best_count = t.count;
    }
  }
  return best_score >= 0 ? best : std::string();
}

int ColorScore(const std::string& name, const TopicData& t) {
  if (!IsImage(t) || Contains(name, "depth")) return -1;
  if (t.type == kCompressed && Contains(name, "compresseddepth")) return -1;
  return 4 * (Contains(name, "color") || Contains(name, "rgb")) +
         2 * (t.type == kImage);
}

int DepthScore(const std::string& name, const TopicData& t) {
  if (!IsImage(t) || !Contains(name, "depth")) return -1;
  return 4 * (Contains(name, "aligned") || Contains(name, "registered")) +
         2 * (t.type == kImage);
}

size_t CommonPrefix(const std::string& a, const std::string& b) {
  size_t n = 0;
  while (n < a.size() && n < b.size() && a[n] == b[n]) ++n;
  return n;
}

// The CameraInfo topic beside `image_topic` (the longest shared prefix).
std::string InfoTopicFor(const BagScan& scan, const std::string& image_topic) {
  std::string best;
  size_t best_n = 0;
  for (const auto& [name, t] : scan.topics) {
    if (t.type != kCameraInfo || t.info.empty()) continue;
    const size_t n = CommonPrefix(name, image_topic);
    if (best.empty() || n > best_n) {
      best = name;
      best_n = n;
    }
  }
  return best;
}

CameraIntrinsics FromInfo(const RosCameraInfo& info) {
  CameraIntrinsics k;
  k.width = static_cast<int>(info.width);
  k.height = static_cast<int>(info.height);
  k.fx = info.k[0];
  k.fy = info.k[4];
  k.cx = info.k[2];
  k.cy = info.k[5];
  return k;
}

// Depth pixels moved into the colour camera (z-buffered; holes stay 0).
struct Registration {
  CameraIntrinsics depth, color;
  Transform T_color_depth;
};

DepthImage Register(const DepthImage& d, const Registration& r) {
  if (!d.SameSize(r.depth.width, r.depth.height)) {
    throw CdrError(
        fmt::format("depth image {}x{} but its CameraInfo says "
                    "{}x{}: cannot register it",
                    d.width(), d.height(), r.depth.width, r.depth.height));
  }
  DepthImage out(r.color.width, r.color.height);
  for (int v = 0; v < d.height(); ++v) {
    for (int u = 0; u < d.width(); ++u) {
      const float z = d(u, v);
      if (z <= 0.0f) continue;
      const Eigen::Vector3d p_depth((u - r.depth.cx) / r.depth.fx * z,
                                    (v - r.depth.cy) / r.depth.fy * z, z);
      const Eigen::Vector3d p = r.T_color_depth * p_depth;
      if (p.z() <= 0.0) continue;
      const double u_c = r.color.fx * p.x() / p.z() + r.color.cx;
      const double v_c = r.color.fy * p.y() / p.z() + r.color.cy;
      if (!(u_c > -0.5 && v_c > -0.5 && u_c < r.color.width - 0.5 &&
            v_c < r.color.height - 0.5)) {
        continue;  // outside the colour image (or not finite)
      }
      const int64_t x = std::lround(u_c), y = std::lround(v_c);
      float& dst = out(static_cast<int>(x), static_cast<int>(y));
      const auto zc = static_cast<float>(p.z());
      if (dst == 0.0f || zc < dst) dst = zc;
    }
  }
  return out;
}

class BagFrames : public FrameSource {
 public:
  struct Pair {
    BagMessageRef color, depth;
  };
  BagFrames(std::unique_ptr<BagStorage> bag, std::string color_type,
            std::string depth_type, std::optional<Registration> registration)
      : bag_(std::move(bag)),
        color_compressed_(color_type == kCompressed),
        depth_compressed_(depth_type == kCompressed),
        registration_(std::move(registration)) {}

  std::vector<Pair> pairs;

 private:
  // One image message, as Image or CompressedImage; errors name the file.
  template <typename Convert>
  auto Decode(const BagMessageRef& ref, size_t i, const char* what,
              bool compressed, Convert&& convert) const {
    std::vector<uint8_t> b;
    {
      // The storage reads (seeks, the cached chunk) one at a time; decoding
      // runs in parallel.
      std::lock_guard<std::mutex> lock(mutex_);
      b = bag_->Read(ref);
    }
    try {
      return compressed ? convert(DecodeRosCompressedImage(b.data(), b.size()))
                        : convert(DecodeRosImage(b.data(), b.size()));
    } catch (const CdrError& e) {
      throw FormatError(bag_->File(ref),
                        fmt::format("frame {} {}: {}", i, what, e.what()));
    }
  }

 public:
  void Read(size_t i, ColorImage* color, DepthImage* depth) const override {
    const Pair& p = pairs.at(i);
    *color = Decode(p.color, i, "colour", color_compressed_,
                    [](auto&& m) { return RosColor(m); });
    *depth = Decode(p.depth, i, "depth", depth_compressed_,
                    [](auto&& m) { return RosDepth(m); });
    if (registration_) {
      try {
        *depth = Register(*depth, *registration_);
      } catch (const CdrError& e) {
        throw FormatError(bag_->File(p.depth),
                          fmt::format("frame {} depth: {}", i, e.what()));
      }
    }
  }

 private:
  mutable std::mutex mutex_;
  std::unique_ptr<BagStorage> bag_;
  bool color_compressed_, depth_compressed_;
  std::optional<Registration> registration_;
};

std::string WorldFrame(const TfTree& tf, const std::string& given,
                       const std::string& camera) {
  if (!given.empty()) return given;
  for (const char* f : {"map", "odom"}) {
    if (!tf.Chain(f, camera).empty()) return f;
  }
  // The root above the camera ("map" when there is none: the lookups then
  // say what is missing).
  std::string root = "map";
  for (const std::string& r : tf.Roots()) {
    if (!tf.Chain(r, camera).empty()) root = r;
  }
  return root;
}

std::vector<std::string> TopicTable(const BagScan& scan) {
  std::vector<std::string> lines = {fmt::format(
      "{:<44} {:<34} {:>7} {:>8}", "topic", "type", "count", "rate Hz")};
  for (const auto& [name, t] : scan.topics) {
    // Log times are the recorder's: any 64-bit values (no overflow here).
    const double span_s = 1e-9 * (static_cast<double>(t.last_ns) -
                                  static_cast<double>(t.first_ns));
    const double rate = t.count > 1 && span_s > 0 ? (t.count - 1) / span_s : 0;
    lines.push_back(fmt::format("{:<44} {:<34} {:>7} {:>8.2f}", name, t.type,
                                t.count, rate));
  }
  return lines;
}

// The chosen topics and what the frames need besides them.
struct Choice {
  std::string color_topic, depth_topic, info_topic;
  std::string camera;  // TF frame of the colour camera
  std::optional<Registration> registration;
  std::string depth_note;
};

Choice ChooseTopics(const BagScan& scan, const fs::path& path,
                    const BagOptions& o) {
  Choice c;
  c.color_topic =
      PickTopic(scan, o.color_topic, ColorScore, path, "colour images");
  if (c.color_topic.empty()) {
    throw FormatError(path,
                      "no colour image topic (sensor_msgs/msg/Image or "
                      "CompressedImage without 'depth' in its name); "
                      "name one with --color-topic");
  }
  c.depth_topic =
      PickTopic(scan, o.depth_topic, DepthScore, path, "depth images");
  if (c.depth_topic.empty()) {
    throw FormatError(path,
                      "no depth image topic (an Image or "
                      "CompressedImage topic with 'depth' in its "
                      "name); name one with --depth-topic");
  }
  c.info_topic = o.camera_info_topic.empty() ? InfoTopicFor(scan, c.color_topic)
                                             : o.camera_info_topic;
  const TopicData& color = scan.topics.at(c.color_topic);
  c.camera = o.camera_frame.empty() ? color.frame_id : o.camera_frame;
  return c;
}

// Intrinsics: an explicit file, else the colour camera's CameraInfo.
// The size of the first colour image (a 3x3 K file has none).
std::pair<int, int> FirstColorSize(BagStorage* bag, const TopicData& color,
                                   const fs::path& path) {
  if (color.messages.empty()) return {0, 0};
  const std::vector<uint8_t> b = bag->Read(color.messages.front().ref);
  try {
    if (color.type == kImage) {
      const RosImage m = DecodeRosImage(b.data(), b.size());
      return {static_cast<int>(m.width), static_cast<int>(m.height)};
    }
    const ColorImage img =
        RosColor(DecodeRosCompressedImage(b.data(), b.size()));
    return {img.width(), img.height()};
  } catch (const CdrError& e) {
    throw FormatError(path, std::string("the first colour image: ") + e.what());
  }
}

void SetIntrinsics(const BagScan& scan, const Choice& c, const fs::path& path,
                   const SequenceReaderOptions& options, BagStorage* bag,
                   SequenceIndex* index) {
  const auto it = scan.topics.find(c.info_topic);
  if (!options.intrinsics_path.empty()) {
    // A 3x3 K file has no image size: the CameraInfo's, else the first
    // colour image's.
    std::pair<int, int> size{0, 0};
    if (it != scan.topics.end() && !it->second.info.empty()) {
      size = {static_cast<int>(it->second.info[0].width),
              static_cast<int>(it->second.info[0].height)};
    } else {
      size = FirstColorSize(bag, scan.topics.at(c.color_topic), path);
    }
    index->intrinsics =
        ReadIntrinsicsFile(options.intrinsics_path, size.first, size.second);
    index->intrinsics_source = options.intrinsics_path.filename().string();
    return;
  }
  if (c.info_topic.empty() || it == scan.topics.end() ||
      it->second.info.empty()) {
    throw FormatError(path, fmt::format("no CameraInfo for the colour topic "
                                        "{}; name one with "
                                        "--camera-info-topic or give "
                                        "--intrinsics",
                                        c.color_topic));
  }
  const RosCameraInfo& info = it->second.info[0];
  index->intrinsics = FromInfo(info);
  const bool undistorted = std::all_of(info.d.begin(), info.d.end(),
                                       [](double v) { return v == 0.0; });
  index->intrinsics_source = fmt::format(
      "{} (distortion model '{}', {})", c.info_topic, info.distortion_model,
      undistorted ? "no distortion" : "distortion not corrected");
}

// Depth in its own optical frame is registered into the colour camera.
void ChooseRegistration(const BagScan& scan, const fs::path& path,
                        const CameraIntrinsics& color_k, Choice* c) {
  const TopicData& color = scan.topics.at(c->color_topic);
  const TopicData& depth = scan.topics.at(c->depth_topic);
  c->depth_note =
      "depth aligned with colour (same frame '" + depth.frame_id + "')";
  if (depth.frame_id.empty() || color.frame_id.empty() ||
      depth.frame_id == color.frame_id) {
    return;
  }
  const std::string depth_info = InfoTopicFor(scan, c->depth_topic);
  std::string why = "no CameraInfo of its own";
  std::optional<Transform> T;
  if (!depth_info.empty() && depth_info != c->info_topic) {
    T = scan.tf.Lookup(
        color.frame_id, depth.frame_id,
        color.messages.empty() ? 0 : color.messages.front().stamp_ns, &why);
  }
  if (!T) {
    throw FormatError(
        path, fmt::format("depth ({}, frame '{}') is not in the "
                          "colour frame '{}' and cannot be "
                          "registered: {}",
                          c->depth_topic, depth.frame_id, color.frame_id, why));
  }
  const CameraIntrinsics depth_k = FromInfo(scan.topics.at(depth_info).info[0]);
  try {
    depth_k.Check();
  } catch (const InvalidArgument& e) {
    throw FormatError(path, fmt::format("the depth camera's CameraInfo ({}) "
                                        "cannot register depth: {}",
                                        depth_info, e.what()));
  }
  c->registration = Registration{depth_k, color_k, *T};
  c->depth_note = fmt::format(
      "depth registered into the colour camera (depth frame '{}', intrinsics "
      "{}, extrinsic from TF)",
      depth.frame_id, depth_info);
}

// The camera's pose at a stamp: from TF (world -> camera), or from a pose
// topic (world -> its child) then TF (child -> camera).
class PoseLookup {
 public:
  PoseLookup(const BagScan& scan, const BagOptions& o,
             const std::string& camera, const fs::path& path)
      : tf_(scan.tf), camera_(camera), use_tf_(o.pose_source == "tf") {
    child_ = camera;
    if (use_tf_) {
      world_ = WorldFrame(scan.tf, o.world_frame, camera);
      const auto chain = scan.tf.Chain(world_, camera);
      source_ = chain.empty()
                    ? fmt::format("TF {} -> {} (not connected)", world_, camera)
                    : fmt::format("TF {}", fmt::join(chain, " -> "));
      return;
    }
    const auto it = scan.topics.find(o.pose_source);
    if (it == scan.topics.end() || it->second.poses.empty()) {
      throw FormatError(path, fmt::format("pose source '{}' is not an "
                                          "Odometry or PoseStamped topic of "
                                          "the bag",
                                          o.pose_source));
    }
    for (RosPose p : it->second.poses) {
      if (p.child_frame_id.empty()) p.child_frame_id = camera;
      world_ = p.header.frame_id;
      child_ = p.child_frame_id;
      poses_.Add({p.header, p.child_frame_id, p.T_parent_child}, false);
    }
    source_ = fmt::format("{} ({} in {}{})", o.pose_source, child_, world_,
                          child_ == camera ? "" : ", then TF to " + camera);
  }

  std::optional<Transform> At(int64_t t_ns, std::string* why) const {
    if (use_tf_) return tf_.Lookup(world_, camera_, t_ns, why);
    const auto T_world_child = poses_.Lookup(world_, child_, t_ns, why);
    if (!T_world_child) return std::nullopt;
    const auto T_child_camera = tf_.Lookup(child_, camera_, t_ns, why);
    if (!T_child_camera) return std::nullopt;
    return *T_world_child * *T_child_camera;
  }
  const std::string& source() const { return source_; }

 private:
  const TfTree& tf_;
  TfTree poses_;
  std::string camera_, world_, child_, source_;
  bool use_tf_;
};

std::vector<Stamped> ByStamp(std::vector<Stamped> v) {
  std::stable_sort(v.begin(), v.end(), [](const Stamped& a, const Stamped& b) {
    return a.stamp_ns < b.stamp_ns;
  });
  return v;
}

// The depth message nearest to `t_ns` within `tol_ns`, or nullptr.
const Stamped* NearestDepth(const std::vector<Stamped>& depths, int64_t t_ns,
                            int64_t tol_ns) {
  const auto after = std::lower_bound(
      depths.begin(), depths.end(), t_ns,
      [](const Stamped& d, int64_t t) { return d.stamp_ns < t; });
  const Stamped* best = nullptr;
  for (auto it : {after, after == depths.begin() ? after : after - 1}) {
    if (it == depths.end()) continue;
    if (!best ||
        std::llabs(it->stamp_ns - t_ns) < std::llabs(best->stamp_ns - t_ns)) {
      best = &*it;
    }
  }
  return best && std::llabs(best->stamp_ns - t_ns) <= tol_ns ? best : nullptr;
}

// Colour frames with a depth image near their stamp and a pose; the others
// are counted (the returned line says how many and why).
std::string PairFrames(const BagScan& scan, const Choice& c,
                       const PoseLookup& poses, const BagOptions& o,
                       const fs::path& path, BagFrames* frames,
                       SequenceIndex* index) {
  const std::vector<Stamped> colors =
      ByStamp(scan.topics.at(c.color_topic).messages);
  const std::vector<Stamped> depths =
      ByStamp(scan.topics.at(c.depth_topic).messages);
  const auto tol_ns = static_cast<int64_t>(o.sync_tol_ms * 1e6);
  size_t no_depth = 0, no_pose = 0;
  std::string first_pose_problem;
  for (const Stamped& color : colors) {
    const Stamped* depth = NearestDepth(depths, color.stamp_ns, tol_ns);
    if (depth == nullptr) {
      ++no_depth;
      continue;
    }
    std::string why;
    const std::optional<Transform> T = poses.At(color.stamp_ns, &why);
    if (!T) {
      if (no_pose++ == 0) first_pose_problem = why;
      continue;
    }
    const size_t i = frames->pairs.size();
    FrameRecord r;
    r.color_path = path / fmt::format("frame-{:06}.color.png", i);
    r.depth_path = path / fmt::format("frame-{:06}.depth.png", i);
    r.T_world_camera = *T;
    r.timestamp_s = 1e-9 * static_cast<double>(color.stamp_ns);
    r.source_index = i;
    frames->pairs.push_back({color.ref, depth->ref});
    index->frames.push_back(std::move(r));
  }
  return fmt::format(
      "frames: {} of {} colour images paired (depth within {} ms); {} "
      "skipped without depth, {} without a pose{}",
      index->frames.size(), colors.size(), o.sync_tol_ms, no_depth, no_pose,
      no_pose ? " (" + first_pose_problem + ")" : "");
}

}  // namespace

std::optional<SequenceIndex> IndexBag(const fs::path& path,
                                      const SequenceReaderOptions& options) {
  std::unique_ptr<BagStorage> bag = OpenBag(path);
  if (!bag) return std::nullopt;
  const BagScan scan = ScanBag(bag.get());
  SequenceIndex index;
  index.layout = "rosbag2 (" + bag->Storage() + ")";
  index.root = path;
  index.depth_scale = 1000.0;  // unused: the frames come decoded
  index.details = TopicTable(scan);
  index.details.push_back("storage: " + bag->Describe());

  Choice choice = ChooseTopics(scan, path, options.bag);
  SetIntrinsics(scan, choice, path, options, bag.get(), &index);
  ChooseRegistration(scan, path, index.intrinsics, &choice);
  const PoseLookup poses(scan, options.bag, choice.camera, path);
  index.pose_source = poses.source();
  const TopicData& color = scan.topics.at(choice.color_topic);
  const TopicData& depth = scan.topics.at(choice.depth_topic);
  auto frames = std::make_shared<BagFrames>(std::move(bag), color.type,
                                            depth.type, choice.registration);
  const std::string pairing =
      PairFrames(scan, choice, poses, options.bag, path, frames.get(), &index);
  index.details.push_back(fmt::format("colour: {} ({}, frame '{}')",
                                      choice.color_topic, color.type,
                                      color.frame_id));
  index.details.push_back(fmt::format("depth: {} ({}); {}", choice.depth_topic,
                                      depth.type, choice.depth_note));
  index.details.push_back(pairing);
  if (scan.undecodable > 0) {
    index.details.push_back(
        fmt::format("{} messages could not be decoded", scan.undecodable));
  }
  if (index.frames.empty()) {
    throw FormatError(path, "no usable frames: " + pairing);
  }
  index.source = std::move(frames);
  return index;
}

}  // namespace semrec::io::internal
