// Every kind of broken input gets a typed error whose message names the file
// and the problem.
#include <fstream>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/io/image_io.h"
#include "semrec/io/ply_io.h"
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

// Headers that promise more than the file holds or more than any camera
// makes are refused before anything is allocated: a few bytes never cost
// gigabytes.
TEST_F(BadInput, HostileSizesAreRefusedBeforeAllocating) {
  auto write = [&](const std::string& name, const std::string& bytes) {
    std::ofstream(Dir() / name, std::ios::binary) << bytes;
    return Dir() / name;
  };
  // PNG: a valid IHDR of 1,000,000 x 1,000,000 16-bit RGBA, no image data.
  auto chunk = [](const std::string& type, const std::string& data) {
    const std::string body = type + data;
    uint32_t crc = 0xFFFFFFFFu;  // CRC-32 of type + data, as PNG wants
    for (unsigned char c : body) {
      crc ^= c;
      for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & -(crc & 1));
    }
    crc ^= 0xFFFFFFFFu;
    std::string out;
    for (uint32_t v : {static_cast<uint32_t>(data.size())}) {
      for (int shift = 24; shift >= 0; shift -= 8) out += char(v >> shift);
    }
    out += body;
    for (int shift = 24; shift >= 0; shift -= 8) out += char(crc >> shift);
    return out;
  };
  auto png_with_size = [&](uint32_t width, uint32_t height) {
    std::string ihdr;
    for (uint32_t v : {width, height}) {
      for (int shift = 24; shift >= 0; shift -= 8) ihdr += char(v >> shift);
    }
    ihdr += std::string("\x10\x06\x00\x00\x00", 5);
    return std::string("\x89PNG\r\n\x1a\n", 8) + chunk("IHDR", ihdr) +
           chunk("IDAT", std::string("\x78\x9c", 2));
  };
  ExpectError<FormatError>(
      [&] { ReadDepthImage(write("big.png", png_with_size(1000000, 1000000))); },
      {"big.png", "1000000 x 1000000", "megapixels"});
  // A plausible size, but far more pixels than 47 bytes can inflate to.
  ExpectError<FormatError>(
      [&] { ReadColorImage(write("4k.png", png_with_size(4096, 4096))); },
      {"4k.png", "more than the file holds"});
  // PGM: 100000 x 100000 16-bit, four bytes of raster.
  ExpectError<FormatError>(
      [&] { ReadDepthImage(write("big.pgm", "P5\n100000 100000\n65535\n1234")); },
      {"big.pgm", "megapixels"});
  ExpectError<FormatError>(
      [&] { ReadDepthImage(write("short.pgm", "P5\n# c\n640 480\n65535\n1234")); },
      {"short.pgm", "truncated"});
  // JPEG: a start-of-frame of 65000 x 65000.
  const std::string sof("\xff\xd8\xff\xc0\x00\x11\x08\xfd\xe8\xfd\xe8\x03\x01\x22\x00\x02\x11\x01\x03\x11\x01", 21);
  ExpectError<FormatError>([&] { ReadColorImage(write("big.jpg", sof)); },
                           {"big.jpg", "65000 x 65000", "megapixels"});
  // Content OpenCV could decode with a codec semrec does not use (DICOM
  // preamble): refused by its signature, whatever the file name says.
  ExpectError<FormatError>(
      [&] { ReadColorImage(write("scan.jpg", std::string(128, '\0') + "DICM")); },
      {"scan.jpg", "not an image semrec reads"});
  // PLY: a billion vertices in a 60-byte file.
  ExpectError<FormatError>(
      [&] {
        ReadPly(write("big.ply",
                      "ply\nformat ascii 1.0\nelement vertex 1000000000\n"
                      "property float x\nend_header\n1\n"));
      },
      {"big.ply", "1000000000", "more than the file holds"});
  ExpectError<FormatError>(
      [&] {
        ReadPly(write("list.ply",
                      "ply\nformat ascii 1.0\nelement face 1\nproperty list "
                      "uint uint vertex_indices\nend_header\n4000000000 1 2\n"));
      },
      {"list.ply", "4000000000"});
}

}  // namespace
}  // namespace semrec::io
