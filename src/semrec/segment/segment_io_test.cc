#include "semrec/segment/segment_io.h"

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/core/label_map.h"
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

TEST(RenderLabelOverlay, BlendsClassColoursOutlinesMasksAndNamesLargeOnes) {
  // A 120 x 90 image: instance 1 (class 3, in the table) on the left, 2 on the
  // right (class 7, not in the table: its colour is LabelColor's), a small
  // instance 3 (under 400 px: no room for a name) inside 2.
  const int w = 120, h = 90;
  ColorImage rgb(w, h, 3);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      for (int c = 0; c < 3; ++c) {
        rgb(x, y, c) = static_cast<uint8_t>((x * 2 + y + 40 * c) % 256);
      }
    }
  }
  LabelMap semantic(w, h), instance(w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const bool left = x < 60;
      const bool small = x >= 90 && x < 100 && y >= 10 && y < 20;
      instance(x, y) = small ? 3 : left ? 1 : 2;
      semantic(x, y) = left ? 3 : 7;
    }
  }
  LabelSet labels("test");
  LabelClass chair;
  chair.id = 3;
  chair.name = "chair";
  chair.color = {200, 10, 100};
  labels.Add(chair);
  const ColorImage out = RenderLabelOverlay(rgb, semantic, instance, labels);
  const auto blend = [&](int x, int y, int c, uint8_t color) {
    return static_cast<uint8_t>((rgb(x, y, c) + color) / 2);
  };
  const std::array<uint8_t, 3> unknown = LabelColor(7);
  // Mask edges are white; away from edges and names, the blend.
  for (int y = 0; y < h; ++y) {
    EXPECT_EQ(out(59, y, 0), 255);
    EXPECT_EQ(out(59, y, 2), 255);
  }
  EXPECT_EQ(out(95, 9, 1), 255);  // above the small instance
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(out(3, 3, c), blend(3, 3, c, chair.color[c]));
    EXPECT_EQ(out(117, 86, c), blend(117, 86, c, unknown[c]));
    EXPECT_EQ(out(95, 15, c), blend(95, 15, c, unknown[c]));
  }
  // A name in each large region, none in the small one.
  const auto drawn = [&](int x0, int x1, int y0, int y1, uint16_t inst) {
    int n = 0;
    for (int y = y0; y < y1; ++y) {
      for (int x = x0; x < x1; ++x) {
        if (instance(x, y) != inst || out(x, y, 0) == 255) continue;
        const uint16_t id = semantic(x, y);
        const std::array<uint8_t, 3> color = id == 3 ? chair.color : unknown;
        for (int c = 0; c < 3; ++c)
          n += out(x, y, c) != blend(x, y, c, color[c]);
      }
    }
    return n;
  };
  EXPECT_GT(drawn(1, 58, 1, h - 1, 1), 20);
  EXPECT_GT(drawn(61, w - 1, 1, h - 1, 2), 20);
  EXPECT_EQ(drawn(91, 99, 11, 19, 3), 0);
  EXPECT_THROW(RenderLabelOverlay(rgb, LabelMap(w, h - 1), instance, labels),
               InvalidArgument);
}

}  // namespace
}  // namespace semrec::segment
