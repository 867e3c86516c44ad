#include "semrec/detect/box.h"

#include <gtest/gtest.h>

namespace semrec::detect {
namespace {

TEST(Box, CornerDistanceIsTheSumOfFourCorners) {
  // Shifted by (3, 4): every corner moves 5 px.
  EXPECT_DOUBLE_EQ(CornerDistance({0, 0, 10, 20}, {3, 4, 10, 20}), 20.0);
  // Grown by 2 px to the right: the two right corners move 2 px.
  EXPECT_DOUBLE_EQ(CornerDistance({0, 0, 10, 20}, {0, 0, 12, 20}), 4.0);
}

TEST(Box, IouOfOverlappingTouchingAndEmptyBoxes) {
  // Half of each 10x10 box overlaps: 50 / (100 + 100 - 50).
  EXPECT_NEAR(Iou({0, 0, 10, 10}, {5, 0, 10, 10}), 50.0 / 150.0, 1e-12);
  EXPECT_DOUBLE_EQ(Iou({0, 0, 10, 10}, {10, 0, 10, 10}), 0.0);
  EXPECT_DOUBLE_EQ(Iou({0, 0, 0, 0}, {0, 0, 0, 0}), 0.0);
  EXPECT_DOUBLE_EQ(Iou({2, 3, 4, 5}, {2, 3, 4, 5}), 1.0);
}

}  // namespace
}  // namespace semrec::detect
