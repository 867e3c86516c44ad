#include "semrec/segment/segment_io.h"

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/io/sequence_reader.h"
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
