#include "semrec/track/box.h"

#include <cmath>

#include <gtest/gtest.h>

#include "semrec/core/random.h"

namespace semrec::track {
namespace {

double CentreError(const Box& a, const Box& b) {
  return std::hypot(a.left + a.width / 2 - b.left - b.width / 2,
                    a.top + a.height / 2 - b.top - b.height / 2);
}

TEST(BoxFilter, StartsAtTheFirstBoxAndHoldsAStaticOne) {
  const Box box{100, 50, 40, 120};
  BoxFilter filter(box);
  for (int i = 0; i < 20; ++i) {
    const Box p = filter.Predict();
    EXPECT_NEAR(p.left, box.left, 1e-6);
    EXPECT_NEAR(p.height, box.height, 1e-6);
    filter.Update(box);
  }
}

TEST(BoxFilter, LearnsAConstantVelocityAndGrowth) {
  // Centre moves (+6, -2) px per frame; the box grows 1% per frame in size
  // (area not exactly linear, the filter tracks it closely anyway).
  auto truth = [](int f) {
    const double s = 1.0 + 0.01 * f;
    const double w = 40 * s, h = 100 * s;
    const double cx = 100 + 6.0 * f, cy = 300 - 2.0 * f;
    return Box{cx - w / 2, cy - h / 2, w, h};
  };
  BoxFilter filter(truth(0));
  for (int f = 1; f <= 15; ++f) {
    filter.Predict();
    filter.Update(truth(f));
  }
  // Predicting 1 and 5 frames ahead without observations (a lost track).
  const Box p1 = filter.Predict();
  EXPECT_LT(CentreError(p1, truth(16)), 0.5);
  EXPECT_NEAR(p1.height, truth(16).height, 1.5);
  for (int f = 17; f <= 20; ++f) filter.Predict();
  EXPECT_LT(CentreError(filter.Estimate(), truth(20)), 2.0);
  // The static model (last box) would be off by 6.3 px per frame.
  EXPECT_GT(CentreError(truth(15), truth(20)), 30.0);
}

TEST(BoxFilter, SmoothsNoisyObservations) {
  Rng rng(7);
  auto truth = [](int f) { return Box{50 + 3.0 * f, 80, 50, 120}; };
  BoxFilter filter(truth(0));
  double raw = 0, filtered = 0;
  int n = 0;
  for (int f = 1; f <= 200; ++f) {
    filter.Predict();
    Box observed = truth(f);
    observed.left += 4.0 * rng.Normal();
    observed.top += 4.0 * rng.Normal();
    filter.Update(observed);
    if (f > 20) {
      raw += std::pow(CentreError(observed, truth(f)), 2);
      filtered += std::pow(CentreError(filter.Estimate(), truth(f)), 2);
      ++n;
    }
  }
  EXPECT_LT(std::sqrt(filtered / n), 0.8 * std::sqrt(raw / n));
}

TEST(BoxFilter, AShrinkingBoxNeverGetsANegativeArea) {
  BoxFilter filter(Box{0, 0, 100, 100});
  for (int f = 1; f <= 5; ++f) {
    filter.Predict();
    filter.Update(Box{0, 0, 100.0 - 19 * f, 100.0 - 19 * f});
  }
  for (int f = 0; f < 50; ++f) {
    const Box p = filter.Predict();
    EXPECT_GE(p.width, 0.0);
    EXPECT_GE(p.height, 0.0);
    EXPECT_FALSE(std::isnan(p.left));
  }
}

}  // namespace
}  // namespace semrec::track
