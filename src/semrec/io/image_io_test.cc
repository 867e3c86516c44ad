#include "semrec/io/image_io.h"

#include <fstream>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "semrec/core/error.h"
#include "semrec/testing/test_util.h"

namespace semrec::io {
namespace {

TEST(ImageIo, Png16RoundTripKeepsEveryBit) {
  semrec::testing::TempDir dir;
  DepthImage16 depth(5, 3, 1);
  for (size_t i = 0; i < depth.values().size(); ++i) {
    depth.values()[i] = static_cast<uint16_t>(i * 4099 + 1);
  }
  depth(4, 2) = 65535;
  WritePng(dir / "d.png", depth);
  EXPECT_EQ(ReadDepthImage(dir / "d.png"), depth);
  // An independent decoder (OpenCV) agrees, so the byte order is right.
  const cv::Mat mat = cv::imread((dir / "d.png").string(), cv::IMREAD_ANYDEPTH);
  ASSERT_EQ(mat.type(), CV_16UC1);
  EXPECT_EQ(mat.at<uint16_t>(1, 2), depth(2, 1));
}

TEST(ImageIo, ColorPngRoundTripAndRgbOrder) {
  semrec::testing::TempDir dir;
  ColorImage color(2, 2, 3);
  color(0, 0, 0) = 255;  // pure red at (0, 0)
  color(1, 1, 2) = 200;
  WritePng(dir / "c.png", color);
  EXPECT_EQ(ReadColorImage(dir / "c.png"), color);
  const cv::Mat bgr = cv::imread((dir / "c.png").string(), cv::IMREAD_COLOR);
  EXPECT_EQ(bgr.at<cv::Vec3b>(0, 0)[2], 255);  // OpenCV stores BGR
  // Through OpenCV's JPEG path the channel order must stay RGB (a uniform red
  // block, so that chroma subsampling cannot blend colours).
  const cv::Mat red_bgr(16, 16, CV_8UC3, cv::Scalar(0, 0, 255));
  cv::imwrite((dir / "c.jpg").string(), red_bgr,
              {cv::IMWRITE_JPEG_QUALITY, 100});
  const ColorImage jpg = ReadColorImage(dir / "c.jpg");
  EXPECT_GT(jpg(0, 0, 0), 200);
  EXPECT_LT(jpg(0, 0, 2), 60);
}

TEST(ImageIo, GreyPngExpandsToRgb) {
  semrec::testing::TempDir dir;
  Image<uint8_t> grey(3, 1, 1);
  grey.values() = {0, 128, 255};
  WritePng(dir / "g.png", grey);
  const ColorImage rgb = ReadColorImage(dir / "g.png");
  EXPECT_EQ(rgb(1, 0, 0), 128);
  EXPECT_EQ(rgb(1, 0, 2), 128);
  EXPECT_EQ(ReadLabelImage(dir / "g.png")(2, 0), 255);
}

TEST(ImageIo, InfoReadsHeaderOnly) {
  semrec::testing::TempDir dir;
  WritePng(dir / "d.png", DepthImage16(7, 4, 1));
  const ImageInfo info = ReadImageInfo(dir / "d.png");
  EXPECT_EQ(info.width, 7);
  EXPECT_EQ(info.height, 4);
  EXPECT_EQ(info.channels, 1);
  EXPECT_EQ(info.bit_depth, 16);
}

}  // namespace
}  // namespace semrec::io
