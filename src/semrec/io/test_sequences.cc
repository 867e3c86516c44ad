#include "semrec/io/test_sequences.h"

#include <fmt/format.h>

#include "semrec/core/image.h"
#include "semrec/io/image_io.h"
#include "semrec/io/pose_io.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/testing/test_util.h"

namespace fs = std::filesystem;

namespace semrec::io::testing {
namespace {

void WriteFrameImages(int i, double depth_scale, const fs::path& color,
                      const fs::path& depth) {
  ColorImage c(kWidth, kHeight, 3);
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      c(x, y, 0) = static_cast<uint8_t>(10 * i);
      c(x, y, 1) = 20;
      c(x, y, 2) = 30;
    }
  }
  WritePng(color, c);
  DepthImage16 d(
      kWidth, kHeight, 1,
      static_cast<uint16_t>(std::lround((1.0 + 0.1 * i) * depth_scale)));
  WritePng(depth, d);
}

std::string MatrixText(const Transform& t) {
  const Eigen::Matrix4d m = t.Matrix();
  std::string s;
  for (int r = 0; r < 4; ++r) {
    s += fmt::format("{} {} {} {}\n", m(r, 0), m(r, 1), m(r, 2), m(r, 3));
  }
  return s;
}

}  // namespace

CameraIntrinsics TestIntrinsics() {
  return {kWidth, kHeight, 10.0, 10.0, 3.5, 2.5};
}

Transform TestPose(int i) {
  return Transform(Eigen::Matrix3d::Identity(), {0.1 * i, 0.0, 0.0});
}

void WriteRedwood(const fs::path& dir, int frames) {
  std::vector<Transform> poses;
  for (int i = 0; i < frames; ++i) {
    WriteFrameImages(i, 1000.0, dir / fmt::format("color/{:05}.png", i),
                     dir / fmt::format("depth/{:05}.png", i));
    poses.push_back(TestPose(i));
  }
  WriteRedwoodLog(dir / "odometry.log", poses);
  const CameraIntrinsics k = TestIntrinsics();
  semrec::testing::WriteText(
      dir / "camera_primesense.json",
      fmt::format(
          R"({{"width": {}, "height": {}, "intrinsic_matrix": [{}, 0, 0, 0, {}, 0, {}, {}, 1]}})",
          k.width, k.height, k.fx, k.fy, k.cx, k.cy));
}

void WriteSevenScenes(const fs::path& dir, int frames) {
  for (int i = 0; i < frames; ++i) {
    const std::string stem = fmt::format("frame-{:06}", i);
    WriteFrameImages(i, 1000.0, dir / (stem + ".color.png"),
                     dir / (stem + ".depth.png"));
    semrec::testing::WriteText(dir / (stem + ".pose.txt"),
                               MatrixText(TestPose(i)));
  }
  const CameraIntrinsics k = TestIntrinsics();
  semrec::testing::WriteText(
      dir / "camera-intrinsics.txt",
      fmt::format("{} 0 {}\n0 {} {}\n0 0 1\n", k.fx, k.cx, k.fy, k.cy));
}

void WriteTum(const fs::path& dir, int frames) {
  std::string rgb = "# color images\n", depth = "# depth images\n",
              gt = "# ground truth\n";
  for (int i = 0; i < frames; ++i) {
    const double t = 100.0 + i / 30.0;
    WriteFrameImages(i, 5000.0, dir / fmt::format("rgb/{:.6f}.png", t + 0.004),
                     dir / fmt::format("depth/{:.6f}.png", t));
    rgb += fmt::format("{:.6f} rgb/{:.6f}.png\n", t + 0.004, t + 0.004);
    depth += fmt::format("{:.6f} depth/{:.6f}.png\n", t, t);
  }
  // Poses at 100 Hz bracketing the frames; camera moves at 3 m/s along x (0.1 m
  // per frame).
  for (int j = -2; j <= frames * 10 / 3 + 2; ++j) {
    const double t = 100.0 + j / 100.0;
    gt += fmt::format("{:.6f} {:.9f} 0 0 0 0 0 1\n", t, 3.0 * (t - 100.0));
  }
  semrec::testing::WriteText(dir / "rgb.txt", rgb);
  semrec::testing::WriteText(dir / "depth.txt", depth);
  semrec::testing::WriteText(dir / "groundtruth.txt", gt);
  const CameraIntrinsics k = TestIntrinsics();
  semrec::testing::WriteText(
      dir / "intrinsics.json",
      fmt::format(
          R"({{"width": {}, "height": {}, "intrinsic_matrix": [{}, 0, 0, 0, {}, 0, {}, {}, 1]}})",
          k.width, k.height, k.fx, k.fy, k.cx, k.cy));
}

void WriteManifestSequence(const fs::path& dir, int frames) {
  SequenceIndex index;
  index.intrinsics = TestIntrinsics();
  index.depth_scale = 1000.0;
  for (int i = 0; i < frames; ++i) {
    FrameRecord r;
    r.color_path = dir / fmt::format("color/{:06}.png", i);
    r.depth_path = dir / fmt::format("depth/{:06}.png", i);
    WriteFrameImages(i, 1000.0, r.color_path, r.depth_path);
    r.T_world_camera = TestPose(i);
    r.timestamp_s = 0.5 * i;
    r.layers["semantic"] = dir / fmt::format("semantic/{:06}.png", i);
    index.frames.push_back(r);
  }
  WriteSequenceManifest(dir / "sequence.yaml", index);
}

}  // namespace semrec::io::testing
