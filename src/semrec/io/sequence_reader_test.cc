#include "semrec/io/sequence_reader.h"

#include <functional>
#include <regex>

#include <gtest/gtest.h>

#include "semrec/io/test_sequences.h"
#include "semrec/testing/test_util.h"

namespace fs = std::filesystem;

namespace semrec::io {
namespace {

struct LayoutCase {
  std::string layout;
  std::function<void(const fs::path&, int)> write;
};

void PrintTo(const LayoutCase& c, std::ostream* os) { *os << c.layout; }

class SequenceReaderLayouts : public ::testing::TestWithParam<LayoutCase> {};

TEST_P(SequenceReaderLayouts, DetectsLayoutAndReadsFramesExactly) {
  semrec::testing::TempDir dir;
  const int n = 4;
  GetParam().write(dir.path(), n);
  const SequenceReader reader = SequenceReader::Open(dir.path());
  EXPECT_EQ(reader.layout(), GetParam().layout);
  ASSERT_EQ(reader.size(), static_cast<size_t>(n));
  EXPECT_EQ(reader.intrinsics(), testing::TestIntrinsics());
  for (int i = 0; i < n; ++i) {
    const Frame frame = reader.Read(i);
    SCOPED_TRACE("frame " + std::to_string(i));
    ASSERT_EQ(frame.depth.width(), testing::kWidth);
    ASSERT_EQ(frame.depth.height(), testing::kHeight);
    EXPECT_NEAR(frame.depth(3, 2), 1.0 + 0.1 * i, 1e-6);
    EXPECT_EQ(frame.color(5, 4, 0), 10 * i);
    EXPECT_EQ(frame.color(5, 4, 1), 20);
    EXPECT_EQ(frame.color(5, 4, 2), 30);
    // TUM timestamps are printed with 6 decimals, so its interpolated poses are
    // off by ~1e-6 m.
    EXPECT_TRUE(frame.T_world_camera.IsApprox(testing::TestPose(i), 1e-5))
        << frame.T_world_camera.Matrix();
  }
  EXPECT_NEAR(reader.TrajectoryLengthM(), 0.1 * (n - 1), 1e-6);
}

INSTANTIATE_TEST_SUITE_P(
    AllLayouts, SequenceReaderLayouts,
    ::testing::Values(LayoutCase{"redwood", testing::WriteRedwood},
                      LayoutCase{"7scenes", testing::WriteSevenScenes},
                      LayoutCase{"tum", testing::WriteTum},
                      LayoutCase{"semrec", testing::WriteManifestSequence}),
    [](const auto& info) { return info.param.layout; });

// Without its pose files a recording is refused, naming the way out, unless
// poses are not required: then it reads with identity poses, for estimation.
TEST(SequenceReader, RecordingsWithoutPosesOpenForEstimation) {
  struct Case {
    const char* layout;
    void (*write)(const std::filesystem::path&, int);
    const char* pose_files;  // removed: a regex of file names
  };
  for (const Case& c :
       {Case{"redwood", testing::WriteRedwood, "[.]log$"},
        Case{"7scenes", testing::WriteSevenScenes, "pose[.]txt$"},
        Case{"tum", testing::WriteTum, "^groundtruth[.]txt$"}}) {
    SCOPED_TRACE(c.layout);
    semrec::testing::TempDir dir;
    c.write(dir.path(), 3);
    const std::regex pose_file(c.pose_files);
    for (const auto& e :
         std::filesystem::recursive_directory_iterator(dir.path())) {
      if (std::regex_search(e.path().filename().string(), pose_file)) {
        std::filesystem::remove(e.path());
      }
    }
    try {
      SequenceReader::Open(dir.path());
      ADD_FAILURE() << "opened without poses";
    } catch (const FileError& e) {
      EXPECT_NE(std::string(e.what()).find("--poses estimate"),
                std::string::npos)
          << e.what();
    }
    SequenceReaderOptions options;
    options.require_poses = false;
    const SequenceReader reader = SequenceReader::Open(dir.path(), options);
    EXPECT_FALSE(reader.index().has_poses);
    EXPECT_EQ(reader.index().pose_source, "none");
    ASSERT_EQ(reader.size(), 3u);
    EXPECT_TRUE(reader.Read(2).T_world_camera.IsApprox(Transform(), 1e-12));
    EXPECT_NEAR(reader.Read(2).depth(3, 2), 1.2, 1e-6);
    // With its poses the same options read them.
    semrec::testing::TempDir full;
    c.write(full.path(), 3);
    EXPECT_TRUE(SequenceReader::Open(full.path(), options).index().has_poses);
  }
}

TEST(SequenceReader, StrideAndMaxFrames) {
  semrec::testing::TempDir dir;
  testing::WriteSevenScenes(dir.path(), 7);
  SequenceReaderOptions options;
  options.stride = 2;
  options.max_frames = 3;
  const SequenceReader reader = SequenceReader::Open(dir.path(), options);
  ASSERT_EQ(reader.size(), 3u);  // frames 0, 2, 4
  EXPECT_TRUE(reader.T_world_camera(2).IsApprox(testing::TestPose(4), 1e-9));
  EXPECT_NEAR(reader.Read(1).depth(0, 0), 1.2, 1e-6);
}

TEST(SequenceReader, MaxDepthMarksFarPixelsInvalid) {
  semrec::testing::TempDir dir;
  testing::WriteSevenScenes(dir.path(), 3);
  SequenceReaderOptions options;
  options.max_depth_m = 1.15;
  const SequenceReader reader = SequenceReader::Open(dir.path(), options);
  EXPECT_GT(reader.Read(1).depth(0, 0), 0.0f);  // 1.1 m
  EXPECT_EQ(reader.Read(2).depth(0, 0), 0.0f);  // 1.2 m
}

TEST(SequenceReader, ManifestRoundTripKeepsLayersAndTimestamps) {
  semrec::testing::TempDir dir;
  testing::WriteManifestSequence(dir.path(), 2);
  // Also opens when given the manifest file itself.
  const SequenceReader reader = SequenceReader::Open(dir / "sequence.yaml");
  ASSERT_EQ(reader.size(), 2u);
  const FrameRecord& f1 = reader.index().frames[1];
  EXPECT_DOUBLE_EQ(f1.timestamp_s, 0.5);
  ASSERT_EQ(f1.layers.count("semantic"), 1u);
  EXPECT_EQ(f1.layers.at("semantic"), dir / "semantic/000001.png");
  // Paths inside the folder are stored relative, so the sequence can be moved.
  const fs::path moved = dir / "moved";
  fs::create_directories(moved);
  for (const char* sub : {"color", "depth", "sequence.yaml"}) {
    fs::rename(dir / sub, moved / sub);
  }
  EXPECT_EQ(SequenceReader::Open(moved).Read(1).depth_path,
            moved / "depth/000001.png");
}

TEST(SequenceReader, ManifestPosesKeepFullPrecision) {
  semrec::testing::TempDir dir;
  testing::WriteManifestSequence(dir.path(), 1);
  SequenceIndex index = SequenceReader::Open(dir.path()).index();
  index.frames[0].T_world_camera =
      Transform(Eigen::AngleAxisd(0.123456789,
                                  Eigen::Vector3d(0.3, -0.5, 0.8).normalized())
                    .toRotationMatrix(),
                Eigen::Vector3d(1.0 / 3.0, -2.0 / 7.0, 1e-7));
  WriteSequenceManifest(dir / "sequence.yaml", index);
  EXPECT_TRUE(SequenceReader::Open(dir.path())
                  .T_world_camera(0)
                  .IsApprox(index.frames[0].T_world_camera, 1e-15));
}

}  // namespace
}  // namespace semrec::io
