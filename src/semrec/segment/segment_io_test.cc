#include "semrec/segment/segment_io.h"

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/io/test_bags.h"
#include "semrec/testing/test_util.h"

namespace semrec::segment {
namespace {

namespace fs = std::filesystem;

TEST(ListSegmentInputs, SevenScenesFolderIsASequenceNotAnImageFolder) {
  // Colour and depth images lie side by side: only the colour images are
  // inputs, named like the depth images (fusion's label folder source).
  SEMREC_REQUIRE_SAMPLE_DATA(chess, "7scenes_chess_0_99");
  EXPECT_TRUE(io::SequenceReader::TryOpen(chess).has_value());
  const auto inputs = ListSegmentInputs(chess, 5);
  ASSERT_EQ(inputs.size(), 20u);
  EXPECT_EQ(inputs[0].name, "frame-000000.depth.png");
  EXPECT_EQ(inputs[0].image.filename(), "frame-000000.color.jpg");
  EXPECT_EQ(inputs[1].image.filename(), "frame-000005.color.jpg");
  EXPECT_EQ(ListSegmentInputs(chess, 1, 7).size(), 7u);
}

TEST(ListSegmentInputs, BagsAndSensFilesAreSequencesReadThroughTheReader) {
  // No image files behind their frames: Load() decodes the messages.
  testing::TempDir dir;
  CameraIntrinsics k;
  k.width = 16;
  k.height = 12;
  k.fx = k.fy = 15;
  k.cx = 7.5;
  k.cy = 5.5;
  std::vector<io::testing::BagFrame> frames(3);
  for (size_t i = 0; i < frames.size(); ++i) {
    frames[i].color = ColorImage(16, 12, 3, static_cast<uint8_t>(40 * i));
    frames[i].depth_m = DepthImage(16, 12, 1, 1.5f);
    frames[i].timestamp_s = 0.1 * static_cast<double>(i);
  }
  io::testing::TestBagOptions bare;
  bare.metadata_yaml = false;
  io::testing::WriteTestBag(dir / "rec.mcap", frames, k, bare);
  io::testing::WriteTestSens(dir / "scene.sens", frames, k, false, 1);
  for (const char* file : {"rec.mcap", "scene.sens"}) {
    const auto inputs = ListSegmentInputs(dir / file, 2);
    ASSERT_EQ(inputs.size(), 2u) << file;
    EXPECT_EQ(inputs[1].name, "frame-000002.depth.png") << file;
    EXPECT_EQ(inputs[1].Load(), frames[2].color) << file;
  }
}

TEST(ListSegmentInputs, ImageFolderFileAndErrors) {
  testing::TempDir dir;
  for (const char* name : {"b.jpg", "a.png", "c.JPEG", "notes.txt"}) {
    testing::WriteText(dir / name, "x");
  }
  EXPECT_FALSE(io::SequenceReader::TryOpen(dir.path()).has_value());
  const auto inputs = ListSegmentInputs(dir.path());
  ASSERT_EQ(inputs.size(), 3u);
  EXPECT_EQ(inputs[0].name, "a.png");
  EXPECT_EQ(inputs[1].name, "b.png");
  EXPECT_EQ(inputs[2].name, "c.png");
  EXPECT_EQ(ListSegmentInputs(dir.path(), 2).size(), 2u);

  const auto one = ListSegmentInputs(dir / "b.jpg");
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0].name, "b.png");
  EXPECT_THROW(ListSegmentInputs(dir / "notes.txt"), FormatError);

  testing::TempDir empty;
  try {
    ListSegmentInputs(empty.path());
    FAIL() << "an empty folder must be refused";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("no images"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(ListSegmentInputs(dir.path(), 0), InvalidArgument);
  EXPECT_FALSE(io::SequenceReader::TryOpen(dir / "missing").has_value());
}

}  // namespace
}  // namespace semrec::segment
