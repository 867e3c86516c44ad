// ROS 2 bags: CDR messages, MCAP and SQLite storage, the TF tree, and bags as
// a sequence layout (the same frames as the folder they were written from).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>

#include "semrec/core/error.h"
#include "semrec/io/image_io.h"
#include "semrec/io/mcap_reader.h"
#include "semrec/io/mcap_writer.h"
#include "semrec/io/ros_messages.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/io/test_bags.h"
#include "semrec/io/test_sequences.h"
#include "semrec/io/tf_tree.h"
#include "semrec/testing/test_util.h"

namespace semrec::io {
namespace {

namespace fs = std::filesystem;
using semrec::testing::TempDir;

RosHeader Stamp(int32_t sec, uint32_t nsec, const std::string& frame) {
  RosHeader h;
  h.stamp_sec = sec;
  h.stamp_nanosec = nsec;
  h.frame_id = frame;
  return h;
}

Transform Pose(double angle, const Eigen::Vector3d& t) {
  return Transform(
      Eigen::AngleAxisd(angle, Eigen::Vector3d(0.3, 1, 0.2).normalized())
          .toRotationMatrix(),
      t);
}

TEST(Cdr, MessagesSurviveEncodingAndDecoding) {
  RosImage img;
  img.header = Stamp(12, 345, "cam");
  img.width = 3;
  img.height = 2;
  img.encoding = "rgb8";
  img.step = 9;
  for (int i = 0; i < 18; ++i) img.data.push_back(static_cast<uint8_t>(i * 7));
  const auto bytes = EncodeRosImage(img);
  const RosImage back = DecodeRosImage(bytes.data(), bytes.size());
  EXPECT_EQ(back.header.frame_id, "cam");
  EXPECT_EQ(back.header.StampNs(), 12000000345);
  EXPECT_EQ(back.encoding, "rgb8");
  EXPECT_EQ(back.data, img.data);
  const ColorImage rgb = RosColor(back);
  EXPECT_EQ(rgb(2, 1, 0), 15 * 7);

  RosCameraInfo info;
  info.header = Stamp(1, 2, "cam");
  info.width = 640;
  info.height = 480;
  info.distortion_model = "plumb_bob";
  info.d = {0.1, -0.2, 0, 0, 0.01};
  info.k = {500, 0, 320, 0, 501, 240, 0, 0, 1};
  const auto ib = EncodeRosCameraInfo(info);
  const RosCameraInfo ib_back = DecodeRosCameraInfo(ib.data(), ib.size());
  EXPECT_EQ(ib_back.d, info.d);
  EXPECT_EQ(ib_back.k, info.k);
  EXPECT_EQ(ib_back.width, 640u);

  const Transform T = Pose(0.7, {1, 2, 3});
  const auto tb = EncodeRosTfMessage(
      {{Stamp(3, 4, "a"), "b", T}, {Stamp(5, 6, "b"), "c", T.Inverse()}});
  const auto tf = DecodeRosTfMessage(tb.data(), tb.size());
  ASSERT_EQ(tf.size(), 2u);
  EXPECT_EQ(tf[1].child_frame_id, "c");
  EXPECT_TRUE(tf[0].T_parent_child.Matrix().isApprox(T.Matrix(), 1e-12));

  const auto ob = EncodeRosOdometry({Stamp(7, 8, "odom"), "base", T});
  const RosPose odom = DecodeRosOdometry(ob.data(), ob.size());
  EXPECT_EQ(odom.child_frame_id, "base");
  EXPECT_TRUE(odom.T_parent_child.Matrix().isApprox(T.Matrix(), 1e-12));
  const auto pb = EncodeRosPoseStamped({Stamp(7, 8, "map"), "", T});
  EXPECT_TRUE(DecodeRosPoseStamped(pb.data(), pb.size())
                  .T_parent_child.Matrix()
                  .isApprox(T.Matrix(), 1e-12));
}

TEST(Cdr, BigEndianMessagesAreRead) {
  // Header {sec 1, nsec 2, frame "ab"}, then height 1, width 1, "16UC1",
  // is_bigendian 1, step 2, data {0x03, 0xE8} = 1000 mm.
  const std::vector<uint8_t> be = {
      0, 0, 0, 0,                               // CDR_BE
      0, 0, 0, 1, 0,    0,   0,   2,            // stamp
      0, 0, 0, 3, 'a',  'b', 0,   0,            // frame_id + pad
      0, 0, 0, 1, 0,    0,   0,   1,            // height, width
      0, 0, 0, 6, '1',  '6', 'U', 'C', '1', 0,  // encoding
      1, 0,                                     // is_bigendian + pad
      0, 0, 0, 2,                               // step
      0, 0, 0, 2, 0x03, 0xE8};                  // data
  const RosImage m = DecodeRosImage(be.data(), be.size());
  EXPECT_EQ(m.header.stamp_sec, 1);
  EXPECT_EQ(m.header.frame_id, "ab");
  EXPECT_EQ(m.encoding, "16UC1");
  EXPECT_FLOAT_EQ(RosDepth(m)(0, 0), 1.0f);
}

TEST(Cdr, CompressedDepthOfFloatDepthIsDequantised) {
  // image_transport stores 32FC1 depth as v = a / d + b in a 16-bit PNG,
  // a and b (float32) after the int32 format in its 12-byte header.
  const float a = 1000.0f, b = 10.0f;
  DepthImage16 v(3, 1);
  v.values() = {0, static_cast<uint16_t>(a / 2.0f + b),
                static_cast<uint16_t>(a / 0.5f + b)};
  TempDir dir;
  WritePng(dir.path() / "d.png", v);
  std::ifstream in(dir.path() / "d.png", std::ios::binary);
  std::vector<uint8_t> png(std::istreambuf_iterator<char>(in), {});
  RosCompressedImage m;
  m.format = "32FC1; compressedDepth png";
  m.data.resize(12, 0);
  std::memcpy(m.data.data() + 4, &a, 4);
  std::memcpy(m.data.data() + 8, &b, 4);
  m.data.insert(m.data.end(), png.begin(), png.end());
  const DepthImage d = RosDepth(m);
  EXPECT_EQ(d(0, 0), 0.0f);
  EXPECT_NEAR(d(1, 0), 2.0f, 1e-5);
  EXPECT_NEAR(d(2, 0), 0.5f, 1e-5);
  m.format = "16UC1; compressedDepth png";  // the same PNG as millimetres
  EXPECT_NEAR(RosDepth(m)(1, 0), 0.51f, 1e-6);
  m.format = "16UC1; compressedDepth";  // older image_transport: PNG
  EXPECT_NEAR(RosDepth(m)(1, 0), 0.51f, 1e-6);
  m.format = "16UC1; compressedDepth rvl";
  EXPECT_THROW(RosDepth(m), CdrError);
}

TEST(Cdr, BrokenMessagesAreClearErrors) {
  RosImage img;
  img.width = 4;
  img.height = 4;
  img.encoding = "rgb8";
  img.step = 12;
  img.data.resize(48);
  auto bytes = EncodeRosImage(img);
  bytes.resize(bytes.size() - 10);
  EXPECT_THROW(DecodeRosImage(bytes.data(), bytes.size()), CdrError);
  const std::vector<uint8_t> junk = {7, 7, 7};
  EXPECT_THROW(DecodeRosTfMessage(junk.data(), junk.size()), CdrError);
  img.encoding = "yuv422";
  EXPECT_THROW(RosColor(img), CdrError);
  img.encoding = "rgb8";
  img.step = 100;  // more than the data holds
  EXPECT_THROW(RosColor(img), CdrError);
  // A TF count far beyond the message is refused before allocating.
  const std::vector<uint8_t> huge = {0, 1, 0, 0, 0xff, 0xff, 0xff, 0x7f};
  EXPECT_THROW(DecodeRosTfMessage(huge.data(), huge.size()), CdrError);
}

struct Written {
  uint16_t channel;
  uint64_t time;
  std::vector<uint8_t> data;
};

std::vector<Written> WriteSample(const fs::path& file,
                                 const McapWriterOptions& options) {
  McapWriter w(file, options);
  const uint16_t s = w.AddSchema("std_msgs/msg/String", "ros2msg", "string d");
  const uint16_t a = w.AddChannel(s, "/a");
  const uint16_t b = w.AddChannel(s, "/b");
  std::vector<Written> out;
  for (int i = 0; i < 200; ++i) {
    std::vector<uint8_t> data(100 + i * 13, static_cast<uint8_t>(i));
    data[0] = static_cast<uint8_t>(i >> 3);
    out.push_back({i % 3 ? a : b, uint64_t{1000} + i, data});
    w.Write(out.back().channel, out.back().time, data);
  }
  w.Close();
  return out;
}

TEST(Mcap, EveryCompressionReadsBackTheMessagesWritten) {
  TempDir dir;
  for (const std::string c : {"", "zstd", "lz4"}) {
    for (const bool chunked : {true, false}) {
      if (!chunked && !c.empty()) continue;
      SCOPED_TRACE("compression '" + c + "' chunked " +
                   std::to_string(chunked));
      McapWriterOptions o;
      o.compression = c;
      o.chunked = chunked;
      o.chunk_bytes = 4096;  // many chunks
      const fs::path file = dir.path() / ("m" + c + ".mcap");
      const auto written = WriteSample(file, o);
      ASSERT_TRUE(IsMcapFile(file));
      McapReader r(file);
      EXPECT_EQ(r.profile(), "ros2");
      std::vector<McapMessageInfo> seen;
      size_t i = 0;
      r.Scan(
          [&](const McapMessageInfo& info, const uint8_t* data, size_t size) {
            ASSERT_LT(i, written.size());
            EXPECT_EQ(info.channel_id, written[i].channel);
            EXPECT_EQ(info.log_time_ns, written[i].time);
            EXPECT_EQ(std::vector<uint8_t>(data, data + size), written[i].data);
            seen.push_back(info);
            ++i;
          });
      EXPECT_EQ(seen.size(), written.size());
      EXPECT_EQ(r.channels().at(written[0].channel).topic, "/b");
      EXPECT_EQ(r.schemas().begin()->second.name, "std_msgs/msg/String");
      if (chunked) {
        EXPECT_GT(r.chunk_compressions().at(c), 10u);
      }
      // Random access, out of order.
      for (size_t k : {150u, 3u, 199u, 0u, 77u}) {
        EXPECT_EQ(r.Read(seen[k].ref), written[k].data);
      }
    }
  }
}

// A frame's colour and depth in different chunks, read in turn: each chunk is
// decompressed once, not once per message.
TEST(Mcap, MessagesReadInTurnFromTwoChunksDecompressEachOnce) {
  TempDir dir;
  McapWriterOptions o;
  o.chunk_bytes = 4096;
  const fs::path file = dir.path() / "turns.mcap";
  const auto written = WriteSample(file, o);
  McapReader r(file);
  std::vector<McapMessageRef> refs;
  r.Scan([&](const McapMessageInfo& info, const uint8_t*, size_t) {
    refs.push_back(info.ref);
  });
  const size_t after_scan = r.chunk_compressions().at("zstd");
  // The first and the last message lie in different chunks.
  ASSERT_NE(refs.front().chunk_offset, refs.back().chunk_offset);
  for (int turn = 0; turn < 10; ++turn) {
    EXPECT_EQ(r.Read(refs.front()), written.front().data);
    EXPECT_EQ(r.Read(refs.back()), written.back().data);
  }
  EXPECT_LE(r.chunk_compressions().at("zstd"), after_scan + 2);
}

TEST(Mcap, DamagedFilesAreClearErrors) {
  TempDir dir;
  McapWriterOptions o;
  o.compression = "";
  o.chunk_bytes = 1 << 20;
  const fs::path file = dir.path() / "a.mcap";
  WriteSample(file, o);
  std::vector<char> bytes;
  {
    std::ifstream in(file, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  auto write = [&](const fs::path& p, const std::vector<char>& b) {
    std::ofstream(p, std::ios::binary)
        .write(b.data(), static_cast<std::streamsize>(b.size()));
  };
  auto scan = [](const fs::path& p) {
    McapReader r(p);
    size_t n = 0;
    r.Scan([&](const McapMessageInfo&, const uint8_t*, size_t) { ++n; });
    return n;
  };
  // A flipped byte inside the (uncompressed) chunk: its CRC says so.
  std::vector<char> flipped = bytes;
  flipped[flipped.size() / 2] ^= 0x5a;
  write(dir.path() / "crc.mcap", flipped);
  try {
    scan(dir.path() / "crc.mcap");
    FAIL() << "no error";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("CRC mismatch"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("crc.mcap"), std::string::npos);
  }
  // An unknown compression name: an lz4 bag with its chunks renamed.
  {
    McapWriterOptions lz;
    lz.compression = "lz4";
    WriteSample(dir.path() / "lz.mcap", lz);
    std::ifstream in(dir.path() / "lz.mcap", std::ios::binary);
    std::vector<char> b(std::istreambuf_iterator<char>(in), {});
    const std::string needle("\x03\0\0\0lz4", 7);
    auto at = std::search(b.begin(), b.end(), needle.begin(), needle.end());
    ASSERT_NE(at, b.end());
    std::copy_n("\x03\0\0\0br9", 7, at);
    write(dir.path() / "br.mcap", b);
  }
  try {
    scan(dir.path() / "br.mcap");
    FAIL() << "no error";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown compression 'br9'"),
              std::string::npos)
        << e.what();
  }
  // Cut short: what came before the cut is read, nothing crashes.
  std::vector<char> cut(bytes.begin(), bytes.begin() + bytes.size() / 3);
  write(dir.path() / "cut.mcap", cut);
  EXPECT_EQ(scan(dir.path() / "cut.mcap"), 0u);  // one chunk: cut inside it
  // Not MCAP at all.
  write(dir.path() / "text.mcap", {'h', 'e', 'l', 'l', 'o', '\n'});
  EXPECT_THROW(McapReader(dir.path() / "text.mcap"), FormatError);
  EXPECT_THROW(McapReader(dir.path() / "missing.mcap"), IoError);
}

TEST(TfTree, ChainsInterpolatesAndRefusesToExtrapolate) {
  TfTree tf;
  const Transform T_a_b = Pose(0.3, {1, 0, 0});
  tf.Add({Stamp(0, 0, "map"), "odom", T_a_b}, true);
  const Transform T0 = Pose(0.0, {0, 0, 0});
  const Transform T1 = Pose(0.8, {2, 4, 0});
  tf.Add({Stamp(10, 0, "odom"), "base", T0}, false);
  tf.Add({Stamp(12, 0, "odom"), "base", T1}, false);
  tf.Add({Stamp(0, 0, "base"), "cam", Pose(-0.2, {0, 0, 1})}, true);
  EXPECT_EQ(tf.Chain("map", "cam"),
            (std::vector<std::string>{"map", "odom", "base", "cam"}));
  const int64_t mid = 11'000'000'000;
  const auto T = tf.Lookup("map", "cam", mid);
  ASSERT_TRUE(T.has_value());
  const Transform T_mid = Pose(0.4, {1, 2, 0});  // half way on one axis
  const Transform expect = T_a_b * T_mid * Pose(-0.2, {0, 0, 1});
  EXPECT_TRUE(T->Matrix().isApprox(expect.Matrix(), 1e-9));
  // Upwards: the inverse.
  const auto up = tf.Lookup("cam", "map", mid);
  ASSERT_TRUE(up.has_value());
  EXPECT_TRUE((*up * *T).Matrix().isApprox(Eigen::Matrix4d::Identity(), 1e-9));
  // Between siblings.
  tf.Add({Stamp(0, 0, "base"), "lidar", Pose(0.1, {0, 1, 0})}, true);
  EXPECT_TRUE(tf.Lookup("lidar", "cam", mid).has_value());
  std::string why;
  EXPECT_FALSE(tf.Lookup("map", "cam", 13'000'000'000, &why).has_value());
  EXPECT_NE(why.find("no extrapolation"), std::string::npos) << why;
  EXPECT_FALSE(tf.Lookup("map", "nowhere", mid, &why).has_value());
  EXPECT_NE(why.find("nowhere"), std::string::npos) << why;
}

// A small RGB-D recording: 32x24, a tilted plane seen from moving poses.
std::vector<testing::BagFrame> Frames(CameraIntrinsics* k) {
  k->width = 32;
  k->height = 24;
  k->fx = k->fy = 30;
  k->cx = 15.5;
  k->cy = 11.5;
  std::vector<testing::BagFrame> frames;
  for (int i = 0; i < 6; ++i) {
    testing::BagFrame f;
    f.color = ColorImage(32, 24, 3);
    f.depth_m = DepthImage(32, 24);
    for (int y = 0; y < 24; ++y) {
      for (int x = 0; x < 32; ++x) {
        f.color(x, y, 0) = static_cast<uint8_t>(8 * x);
        f.color(x, y, 1) = static_cast<uint8_t>(10 * y);
        f.color(x, y, 2) = static_cast<uint8_t>(40 * i);
        f.depth_m(x, y) =
            0.001f * static_cast<float>(1500 + 10 * x + 3 * y + i);
      }
    }
    f.T_world_camera = Pose(0.1 * i, {0.2 * i, 0.1, 1.0 - 0.05 * i});
    f.timestamp_s = 0.1 * i;
    frames.push_back(std::move(f));
  }
  return frames;
}

void ExpectSameFrames(const SequenceReader& bag,
                      const std::vector<testing::BagFrame>& frames,
                      bool lossy_color, double pose_tolerance = 1e-9) {
  ASSERT_EQ(bag.size(), frames.size());
  for (size_t i = 0; i < frames.size(); ++i) {
    const Frame f = bag.Read(i);
    EXPECT_TRUE(f.T_world_camera.Matrix().isApprox(
        frames[i].T_world_camera.Matrix(), pose_tolerance))
        << "frame " << i;
    ASSERT_TRUE(f.depth.SameSize(32, 24));
    for (int y = 0; y < 24; ++y) {
      for (int x = 0; x < 32; ++x) {
        ASSERT_NEAR(f.depth(x, y), frames[i].depth_m(x, y), 1e-6);
      }
    }
    if (lossy_color) {
      double err = 0;
      for (size_t v = 0; v < f.color.values().size(); ++v) {
        err += std::abs(f.color.values()[v] - frames[i].color.values()[v]);
      }
      EXPECT_LT(err / f.color.values().size(), 6.0) << "frame " << i;
    } else {
      EXPECT_EQ(f.color, frames[i].color) << "frame " << i;
    }
  }
}

TEST(BagLayout, BagsGiveTheFramesTheyWereWrittenFrom) {
  TempDir dir;
  CameraIntrinsics k;
  const auto frames = Frames(&k);
  struct Case {
    const char* name;
    testing::TestBagOptions o;
    bool lossy;
  };
  std::vector<Case> cases(6);
  cases[0] = {"zstd", {}, false};
  cases[1] = {"lz4-bgr", {}, false};
  cases[1].o.compression = "lz4";
  cases[1].o.bgr = true;
  cases[2] = {"plain-compressed", {}, true};
  cases[2].o.compression = "";
  cases[2].o.chunk_crc = false;
  cases[2].o.compressed_color = true;
  cases[2].o.compressed_depth = true;
  cases[3] = {"sqlite", {}, false};
  cases[3].o.storage = "sqlite3";
  cases[4] = {"bare.mcap", {}, false};
  cases[4].o.metadata_yaml = false;
  cases[5] = {"bare.db3", {}, false};
  cases[5].o.storage = "sqlite3";
  cases[5].o.metadata_yaml = false;
  cases.push_back({"float-depth", {}, false});
  cases.back().o.float_depth = true;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const fs::path bag = dir.path() / c.name;
    testing::WriteTestBag(bag, frames, k, c.o);
    const SequenceReader r = SequenceReader::Open(bag);
    EXPECT_EQ(r.layout().rfind("rosbag2", 0), 0u) << r.layout();
    EXPECT_EQ(r.intrinsics().fx, 30);
    EXPECT_EQ(r.intrinsics().width, 32);
    EXPECT_NE(
        r.index().pose_source.find("map -> odom -> base_link -> camera_link -> "
                                   "camera_color_optical_frame"),
        std::string::npos)
        << r.index().pose_source;
    ExpectSameFrames(r, frames, c.lossy);
  }
}

TEST(BagLayout, DepthInItsOwnFrameIsRegisteredIntoTheColourCamera) {
  TempDir dir;
  CameraIntrinsics k;
  auto frames = Frames(&k);
  frames.resize(1);
  // A wall 2 m ahead, parallel to the image: the same depth in both cameras.
  for (float& d : frames[0].depth_m.values()) d = 2.0f;
  testing::TestBagOptions o;
  o.depth_baseline_m = 0.4;  // 6 px at 2 m with fx 30
  testing::WriteTestBag(dir.path() / "bag", frames, k, o);
  const SequenceReader r = SequenceReader::Open(dir.path() / "bag");
  bool said = false;
  for (const std::string& d : r.index().details) {
    said |= d.find("registered into the colour camera") != std::string::npos;
  }
  EXPECT_TRUE(said);
  const Frame f = r.Read(0);
  // The depth camera sits 0.4 m to the right: its view covers the colour
  // image's right part, the leftmost 6 columns stay holes.
  for (int y = 0; y < 24; ++y) {
    for (int x = 0; x < 32; ++x) {
      if (x < 6) {
        EXPECT_EQ(f.depth(x, y), 0.0f) << x << "," << y;
      } else {
        EXPECT_FLOAT_EQ(f.depth(x, y), 2.0f) << x << "," << y;
      }
    }
  }
}

TEST(BagLayout, PosesFromAnOdometryTopicChainedToTheCameraByTf) {
  TempDir dir;
  CameraIntrinsics k;
  const auto frames = Frames(&k);
  testing::TestBagOptions o;
  o.odometry = true;
  testing::WriteTestBag(dir.path() / "bag", frames, k, o);
  SequenceReaderOptions ro;
  ro.bag.pose_source = "/odom";
  const SequenceReader r = SequenceReader::Open(dir.path() / "bag", ro);
  EXPECT_NE(r.index().pose_source.find("base_link in map, then TF"),
            std::string::npos)
      << r.index().pose_source;
  ExpectSameFrames(r, frames, false);
  ro.bag.pose_source = "/tf";  // not a pose topic
  EXPECT_THROW(SequenceReader::Open(dir.path() / "bag", ro), FormatError);
}

TEST(BagLayout, ReviewedEdgeCases) {
  TempDir dir;
  CameraIntrinsics k;
  const auto frames = Frames(&k);
  // A namespaced robot: /robot1/tf_static holds at every time.
  testing::TestBagOptions ns;
  ns.tf_namespace = "/robot1";
  testing::WriteTestBag(dir.path() / "ns", frames, k, ns);
  ExpectSameFrames(SequenceReader::Open(dir.path() / "ns"), frames, false);
  // A 3x3 K file for a bag: the image size comes from the bag.
  std::ofstream(dir.path() / "K.txt") << "31 0 15.5\n0 31 11.5\n0 0 1\n";
  SequenceReaderOptions with_k;
  with_k.intrinsics_path = dir.path() / "K.txt";
  const SequenceReader r = SequenceReader::Open(dir.path() / "ns", with_k);
  EXPECT_EQ(r.intrinsics().fx, 31);
  EXPECT_EQ(r.intrinsics().width, 32);
  // Another tool's metadata.yaml does not make a folder a bag.
  fs::create_directories(dir.path() / "tum");
  io::testing::WriteTum(dir.path() / "tum", 3);
  std::ofstream(dir.path() / "tum" / "metadata.yaml") << "camera: kinect\n";
  EXPECT_EQ(SequenceReader::Open(dir.path() / "tum").layout(), "tum");
  // A compressed rosbag2 bag is named as such.
  testing::WriteTestBag(dir.path() / "zipped", frames, k, {});
  std::ofstream(dir.path() / "zipped" / "metadata.yaml", std::ios::app)
      << "  compression_mode: FILE\n  compression_format: zstd\n";
  try {
    SequenceReader::Open(dir.path() / "zipped");
    FAIL() << "no error";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("compressed rosbag2 bag"),
              std::string::npos)
        << e.what();
  }
}

TEST(BagLayout, BagsWithoutDepthOrPosesAreClearErrors) {
  TempDir dir;
  CameraIntrinsics k;
  const auto frames = Frames(&k);
  testing::TestBagOptions no_depth;
  no_depth.depth = false;
  testing::WriteTestBag(dir.path() / "no_depth", frames, k, no_depth);
  try {
    SequenceReader::Open(dir.path() / "no_depth");
    FAIL() << "no error";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("no depth image topic"),
              std::string::npos)
        << e.what();
  }
  testing::TestBagOptions no_tf;
  no_tf.tf = false;
  testing::WriteTestBag(dir.path() / "no_tf", frames, k, no_tf);
  try {
    SequenceReader::Open(dir.path() / "no_tf");
    FAIL() << "no error";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("without a pose"), std::string::npos)
        << e.what();
  }
  // Depth too far from the colour stamps: frames skipped and counted.
  testing::TestBagOptions late;
  late.depth_offset_ms = 30.0;
  testing::WriteTestBag(dir.path() / "late", frames, k, late);
  EXPECT_THROW(SequenceReader::Open(dir.path() / "late"), FormatError);
  SequenceReaderOptions wide;
  wide.bag.sync_tol_ms = 40.0;
  EXPECT_EQ(SequenceReader::Open(dir.path() / "late", wide).size(),
            frames.size());
  // A topic that does not exist.
  SequenceReaderOptions named;
  named.bag.color_topic = "/nope";
  EXPECT_THROW(SequenceReader::Open(dir.path() / "late", named), FormatError);
}

TEST(Sens, ScanNetFilesReadBackTheirFrames) {
  TempDir dir;
  CameraIntrinsics k;
  const auto frames = Frames(&k);
  // Lossless colour at the depth size: every frame exactly, frame 2 with
  // ScanNet's invalid pose skipped.
  testing::WriteTestSens(dir.path() / "a.sens", frames, k, false, 1, {2});
  const SequenceReader r = SequenceReader::Open(dir.path() / "a.sens");
  EXPECT_EQ(r.layout(), "scannet-sens");
  ASSERT_EQ(r.size(), frames.size() - 1);
  EXPECT_NE(r.index().details[0].find("1 skipped with an invalid pose"),
            std::string::npos)
      << r.index().details[0];
  std::vector<testing::BagFrame> kept = frames;
  kept.erase(kept.begin() + 2);
  for (size_t i = 0; i < kept.size(); ++i) {
    const Frame f = r.Read(i);
    EXPECT_EQ(f.color, kept[i].color) << i;
    ASSERT_TRUE(f.depth.SameSize(kept[i].depth_m));
    for (size_t p = 0; p < f.depth.values().size(); ++p) {
      ASSERT_NEAR(f.depth.values()[p], kept[i].depth_m.values()[p], 1e-6);
    }
    // Poses are stored as float.
    EXPECT_TRUE(f.T_world_camera.Matrix().isApprox(
        kept[i].T_world_camera.Matrix(), 1e-6));
  }
  // JPEG colour at twice the depth size (as ScanNet's 1296x968 vs 640x480)
  // in a folder: resized to the depth size, intrinsics the depth camera's.
  fs::create_directories(dir.path() / "scene0000_00");
  testing::WriteTestSens(dir.path() / "scene0000_00" / "scene0000_00.sens",
                         frames, k, true, 2);
  const SequenceReader big = SequenceReader::Open(dir.path() / "scene0000_00");
  EXPECT_EQ(big.intrinsics().fx, 30);
  EXPECT_EQ(big.intrinsics().width, 32);
  ExpectSameFrames(big, frames, true, 1e-6);  // .sens stores float poses
}

TEST(Sens, DamagedFilesAreClearErrors) {
  TempDir dir;
  CameraIntrinsics k;
  const auto frames = Frames(&k);
  testing::WriteTestSens(dir.path() / "a.sens", frames, k, false, 1);
  std::vector<char> bytes;
  {
    std::ifstream in(dir.path() / "a.sens", std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  auto expect_error = [&](const std::vector<char>& b, const std::string& what) {
    const fs::path p = dir.path() / "bad.sens";
    std::ofstream(p, std::ios::binary)
        .write(b.data(), static_cast<std::streamsize>(b.size()));
    try {
      SequenceReader::Open(p).Read(0);
      FAIL() << "no error for " << what;
    } catch (const FormatError& e) {
      EXPECT_NE(std::string(e.what()).find("bad.sens"), std::string::npos);
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos)
          << e.what();
    }
  };
  expect_error({bytes.begin(), bytes.begin() + bytes.size() / 2},
               "truncated .sens file");
  std::vector<char> v3 = bytes;
  v3[0] = 3;
  expect_error(v3, ".sens version 3 is not read");
}

}  // namespace
}  // namespace semrec::io
