// Every kind of broken input gets a typed error whose message names the file
// and the problem.
#include <fstream>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/io/image_io.h"
#include "semrec/io/pose_io.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/io/test_sequences.h"
#include "semrec/testing/test_util.h"

namespace fs = std::filesystem;

namespace semrec::io {
namespace {

// Runs `fn`, expects exception E, and checks that its message contains every
// one of `parts`.
template <typename E, typename Fn>
void ExpectError(Fn fn, const std::vector<std::string>& parts) {
  try {
    fn();
    ADD_FAILURE() << "expected an exception";
  } catch (const E& e) {
    const std::string message = e.what();
    for (const std::string& part : parts) {
      EXPECT_NE(message.find(part), std::string::npos)
          << "message \"" << message << "\" lacks \"" << part << "\"";
    }
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type: " << e.what();
  }
}

void ReadAll(const fs::path& path) {
  const SequenceReader reader = SequenceReader::Open(path);
  for (size_t i = 0; i < reader.size(); ++i) reader.Read(i);
}

class BadInput : public ::testing::Test {
 protected:
  semrec::testing::TempDir dir_;
  fs::path Dir() const { return dir_.path(); }
};

TEST_F(BadInput, MissingFolder) {
  ExpectError<IoError>([&] { SequenceReader::Open(Dir() / "nope"); },
                       {(Dir() / "nope").string(), "does not exist"});
}

TEST_F(BadInput, UnknownLayout) {
  semrec::testing::WriteText(Dir() / "notes.txt", "hello");
  ExpectError<IoError>([&] { SequenceReader::Open(Dir()); },
                       {Dir().string(), "no known RGB-D layout"});
}

TEST_F(BadInput, CorruptPng) {
  testing::WriteSevenScenes(Dir(), 2);
  semrec::testing::WriteText(Dir() / "frame-000001.depth.png",
                             "\x89PNG\r\n\x1a\nthis is not a png");
  // The header check at Open only reads frame 0; frame 1 fails when read.
  const SequenceReader reader = SequenceReader::Open(Dir());
  ExpectError<FormatError>([&] { reader.Read(1); },
                           {"frame-000001.depth.png", "corrupt PNG"});
}

TEST_F(BadInput, TruncatedPng) {
  testing::WriteSevenScenes(Dir(), 2);
  const fs::path png = Dir() / "frame-000001.color.png";
  fs::resize_file(png, fs::file_size(png) / 2);
  ExpectError<FormatError>([&] { ReadAll(Dir()); },
                           {"frame-000001.color.png", "corrupt PNG"});
}

TEST_F(BadInput, NotAPngAtAll) {
  semrec::testing::WriteText(Dir() / "x.png", "plain text");
  ExpectError<FormatError>([&] { ReadDepthImage(Dir() / "x.png"); },
                           {"x.png", "not a PNG file"});
}

TEST_F(BadInput, CorruptJpeg) {
  testing::WriteSevenScenes(Dir(), 1);
  fs::remove(Dir() / "frame-000000.color.png");
  semrec::testing::WriteText(Dir() / "frame-000000.color.jpg",
                             "\xff\xd8\xff\xe0 garbage");
  ExpectError<FormatError>([&] { ReadAll(Dir()); },
                           {"frame-000000.color.jpg", "cannot decode"});
}

TEST_F(BadInput, EightBitDepth) {
  testing::WriteSevenScenes(Dir(), 2);
  WritePng(Dir() / "frame-000001.depth.png",
           Image<uint8_t>(testing::kWidth, testing::kHeight, 1));
  ExpectError<FormatError>([&] { ReadAll(Dir()); },
                           {"frame-000001.depth.png", "16-bit", "8 bits"});
}

TEST_F(BadInput, DepthOfWrongSize) {
  testing::WriteSevenScenes(Dir(), 2);
  WritePng(Dir() / "frame-000001.depth.png", DepthImage16(4, 3, 1));
  ExpectError<FormatError>([&] { ReadAll(Dir()); },
                           {"frame-000001.depth.png", "4x3", "8x6"});
}

TEST_F(BadInput, ColorDepthSizeMismatch) {
  testing::WriteSevenScenes(Dir(), 2);
  WritePng(Dir() / "frame-000001.color.png", ColorImage(16, 12, 3));
  ExpectError<FormatError>([&] { ReadAll(Dir()); },
                           {"frame-000001.color.png", "16x12", "8x6"});
}

TEST_F(BadInput, PoseFileWithTooFewRows) {
  testing::WriteSevenScenes(Dir(), 2);
  semrec::testing::WriteText(Dir() / "frame-000001.pose.txt",
                             "1 0 0 0\n0 1 0 0\n0 0 1 0\n");
  ExpectError<FormatError>([&] { SequenceReader::Open(Dir()); },
                           {"frame-000001.pose.txt", "4 rows", "got 3"});
}

TEST_F(BadInput, RedwoodLogWithTooFewRows) {
  testing::WriteRedwood(Dir(), 2);
  semrec::testing::WriteText(
      Dir() / "odometry.log",
      "0 0 1\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n1 1 2\n1 0 0 0\n");
  ExpectError<FormatError>([&] { SequenceReader::Open(Dir()); },
                           {"odometry.log", "too few rows"});
}

TEST_F(BadInput, NonFinitePose) {
  testing::WriteSevenScenes(Dir(), 2);
  semrec::testing::WriteText(Dir() / "frame-000001.pose.txt",
                             "1 0 0 nan\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  ExpectError<FormatError>([&] { SequenceReader::Open(Dir()); },
                           {"frame-000001.pose.txt", "non-finite"});
}

TEST_F(BadInput, NonRigidPose) {
  testing::WriteSevenScenes(Dir(), 2);
  semrec::testing::WriteText(Dir() / "frame-000001.pose.txt",
                             "2 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  ExpectError<FormatError>([&] { SequenceReader::Open(Dir()); },
                           {"frame-000001.pose.txt", "not orthonormal"});
}

TEST_F(BadInput, NonNumericPose) {
  testing::WriteSevenScenes(Dir(), 1);
  semrec::testing::WriteText(Dir() / "frame-000000.pose.txt",
                             "1 0 0 0\n0 1 x 0\n0 0 1 0\n0 0 0 1\n");
  ExpectError<FormatError>(
      [&] { SequenceReader::Open(Dir()); },
      {"frame-000000.pose.txt", "line 2", "'x' is not a number"});
}

TEST_F(BadInput, FewerPosesThanFrames) {
  testing::WriteRedwood(Dir(), 3);
  WriteRedwoodLog(Dir() / "odometry.log",
                  {testing::TestPose(0), testing::TestPose(1)});
  ExpectError<FormatError>([&] { SequenceReader::Open(Dir()); },
                           {"odometry.log", "2 poses for 3 frames"});
}

TEST_F(BadInput, MissingPoseFileForAFrame) {
  testing::WriteSevenScenes(Dir(), 3);
  fs::remove(Dir() / "frame-000002.pose.txt");
  ExpectError<FormatError>([&] { SequenceReader::Open(Dir()); },
                           {"frame-000002.pose.txt", "pose file missing"});
}

TEST_F(BadInput, ColorAndDepthCountsDiffer) {
  testing::WriteRedwood(Dir(), 3);
  fs::remove(Dir() / "color/00002.png");
  ExpectError<FormatError>([&] { SequenceReader::Open(Dir()); },
                           {"2 colour images", "3 depth images"});
}

TEST_F(BadInput, EmptySequence) {
  fs::create_directories(Dir() / "color");
  fs::create_directories(Dir() / "depth");
  ExpectError<FormatError>([&] { SequenceReader::Open(Dir()); },
                           {(Dir() / "depth").string(), "no depth images"});
  // An empty manifest is an empty sequence too.
  semrec::testing::TempDir other;
  semrec::testing::WriteText(
      other / "sequence.yaml",
      "format: semrec-sequence\nversion: 1\nintrinsics: {width: 8, height: "
      "6, fx: 10, fy: 10, cx: 3.5, cy: 2.5}\nframes: []\n");
  ExpectError<FormatError>([&] { SequenceReader::Open(other.path()); },
                           {other.path().string(), "no frames"});
}

TEST_F(BadInput, ManifestErrorsNameKeyAndFrame) {
  testing::WriteManifestSequence(Dir(), 2);
  const fs::path manifest = Dir() / "sequence.yaml";
  std::string text;
  {
    std::ifstream in(manifest);
    text.assign(std::istreambuf_iterator<char>(in), {});
  }
  const auto pos = text.find("T_world_camera", text.find("depth/000001"));
  semrec::testing::WriteText(manifest, text.substr(0, pos) + "T_world: [1]\n");
  ExpectError<FormatError>([&] { SequenceReader::Open(Dir()); },
                           {"sequence.yaml", "frame 1", "T_world_camera"});
  semrec::testing::WriteText(manifest, "format: [unclosed\n");
  ExpectError<FormatError>([&] { SequenceReader::Open(Dir()); },
                           {"sequence.yaml", "invalid YAML"});
}

TEST_F(BadInput, TumWithoutAssociations) {
  testing::WriteTum(Dir(), 2);
  semrec::testing::WriteText(Dir() / "groundtruth.txt",
                             "500.0 0 0 0 0 0 0 1\n");
  ExpectError<FormatError>(
      [&] { SequenceReader::Open(Dir()); },
      {Dir().string(), "no depth image could be associated"});
}

TEST_F(BadInput, BadOptions) {
  testing::WriteSevenScenes(Dir(), 1);
  SequenceReaderOptions options;
  options.stride = 0;
  ExpectError<InvalidArgument>([&] { SequenceReader::Open(Dir(), options); },
                               {"stride"});
  const SequenceReader reader = SequenceReader::Open(Dir());
  ExpectError<InvalidArgument>([&] { reader.Read(5); },
                               {"frame 5 out of range"});
}

}  // namespace
}  // namespace semrec::io
