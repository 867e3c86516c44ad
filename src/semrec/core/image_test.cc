#include "semrec/core/image.h"

#include <gtest/gtest.h>

namespace semrec {
namespace {

TEST(Image, IndexingIsRowMajorInterleaved) {
  ColorImage image(4, 3, 3);
  image(2, 1, 1) = 7;
  EXPECT_EQ(image.values()[(1 * 4 + 2) * 3 + 1], 7);
  EXPECT_EQ(image.NumPixels(), 12u);
  EXPECT_THROW(ColorImage(-1, 3, 3), InvalidArgument);
}

TEST(Image, DepthToMetersHandlesScaleInvalidAndCutoff) {
  DepthImage16 raw(4, 1, 1);
  raw.values() = {0, 1000, 65535, 5000};
  const DepthImage m =
      DepthToMeters(raw, 1000.0, /*invalid_value=*/65535, /*max_depth_m=*/4.0);
  EXPECT_FLOAT_EQ(m(0, 0), 0.0f);  // 0 is invalid
  EXPECT_FLOAT_EQ(m(1, 0), 1.0f);
  EXPECT_FLOAT_EQ(m(2, 0), 0.0f);  // the sensor's invalid marker
  EXPECT_FLOAT_EQ(m(3, 0), 0.0f);  // 5 m is beyond the cut-off
  const DepthImage tum = DepthToMeters(raw, 5000.0);
  EXPECT_FLOAT_EQ(tum(3, 0), 1.0f);
  EXPECT_THROW(DepthToMeters(raw, 0.0), InvalidArgument);
}

}  // namespace
}  // namespace semrec
