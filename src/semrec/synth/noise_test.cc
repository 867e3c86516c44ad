#include "semrec/synth/noise.h"

#include <cmath>

#include <gtest/gtest.h>

#include "semrec/core/error.h"

namespace semrec::synth {
namespace {

const CameraIntrinsics kVga{640, 480, 525.0, 525.0, 319.5, 239.5};

struct Stats {
  double mean = 0, std = 0;
  size_t n = 0;
};
Stats Measure(const DepthImage& d) {
  Stats s;
  for (float v : d.values()) {
    if (v <= 0) continue;
    s.mean += v;
    ++s.n;
  }
  s.mean /= s.n;
  for (float v : d.values()) {
    if (v > 0) s.std += (v - s.mean) * (v - s.mean);
  }
  s.std = std::sqrt(s.std / (s.n - 1));
  return s;
}

class NoiseStatistics : public ::testing::TestWithParam<double> {};

// A fronto-parallel wall at z: the measured spread matches the model within
// 10%.
TEST_P(NoiseStatistics, MatchesTheKinectModel) {
  const double z = GetParam();
  const DepthImage clean(640, 480, 1, static_cast<float>(z));
  const Image<float> facing(640, 480, 1, 1.0f);
  DepthNoiseOptions options;
  options.disparity_step_px = 0.0;  // axial noise alone first
  const Stats axial =
      Measure(ApplyDepthNoise(clean, facing, kVga, options, 11));
  const double sigma = KinectAxialSigmaM(z);
  EXPECT_NEAR(axial.mean, z, 0.1 * sigma);
  EXPECT_NEAR(axial.std, sigma, 0.1 * sigma);
  EXPECT_EQ(axial.n, clean.NumPixels());

  // With disparity quantisation (step dz = z^2 s / (b f)), the spread is
  // sqrt(sigma^2 + dz^2/12).
  options.disparity_step_px = 0.125;
  const Stats quantised =
      Measure(ApplyDepthNoise(clean, facing, kVga, options, 12));
  const double dz = z * z * 0.125 / (options.baseline_m * kVga.fx);
  const double expected = std::sqrt(sigma * sigma + dz * dz / 12);
  EXPECT_NEAR(quantised.mean, z, 0.1 * expected);
  EXPECT_NEAR(quantised.std, expected, 0.1 * expected);
}

INSTANTIATE_TEST_SUITE_P(Depths, NoiseStatistics, ::testing::Values(1.0, 3.0));

TEST(DepthNoise, StrengthScalesSigma) {
  const DepthImage clean(320, 240, 1, 2.0f);
  const Image<float> facing(320, 240, 1, 1.0f);
  DepthNoiseOptions options;
  options.disparity_step_px = 0.0;
  options.strength = 2.0;
  const Stats s =
      Measure(ApplyDepthNoise(clean, facing, kVga.Scaled(0.5), options, 3));
  EXPECT_NEAR(s.std, 2.0 * KinectAxialSigmaM(2.0),
              0.1 * 2.0 * KinectAxialSigmaM(2.0));
}

TEST(DepthNoise, GrazingAnglesEdgesAndRangeDropOut) {
  DepthImage clean(20, 10, 1, 1.0f);
  Image<float> cos_incidence(20, 10, 1, 1.0f);
  for (int v = 0; v < 10; ++v) {
    for (int u = 10; u < 20; ++u) clean(u, v) = 2.0f;  // a depth step at u = 10
    cos_incidence(0, v) = std::cos(85.0 * M_PI / 180.0);
    clean(19, v) = 5.0f;  // beyond the 4 m cut-off
  }
  DepthNoiseOptions options;
  options.strength = 0.0;  // only deterministic effects
  options.disparity_step_px = 0.0;
  const DepthImage out =
      ApplyDepthNoise(clean, cos_incidence, kVga, options, 1);
  for (int v = 0; v < 10; ++v) {
    EXPECT_EQ(out(0, v), 0.0f) << "grazing";
    EXPECT_FLOAT_EQ(out(9, v), 1.0f) << "near side of the edge stays";
    EXPECT_EQ(out(10, v), 0.0f) << "far side of the edge drops";
    EXPECT_FLOAT_EQ(out(11, v), 2.0f);
    EXPECT_EQ(out(19, v), 0.0f) << "beyond max depth";
  }
}

TEST(DepthNoise, DeterministicPerSeedAndOffIsExact) {
  const DepthImage clean(64, 48, 1, 1.5f);
  const Image<float> facing(64, 48, 1, 1.0f);
  DepthNoiseOptions options;
  EXPECT_EQ(ApplyDepthNoise(clean, facing, kVga, options, 5),
            ApplyDepthNoise(clean, facing, kVga, options, 5));
  EXPECT_NE(ApplyDepthNoise(clean, facing, kVga, options, 5),
            ApplyDepthNoise(clean, facing, kVga, options, 6));
  options.enabled = false;
  EXPECT_EQ(ApplyDepthNoise(clean, facing, kVga, options, 5), clean);
  options.strength = -1;
  EXPECT_THROW(ApplyDepthNoise(clean, facing, kVga, options, 5),
               InvalidArgument);
}

}  // namespace
}  // namespace semrec::synth
