#include "semrec/pipeline/people_tracker.h"

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/testing/test_util.h"

namespace semrec::pipeline {
namespace {

struct PixelRect {
  int x, y, w, h;
  std::array<uint8_t, 3> color;
};

ColorImage Scene(const std::vector<PixelRect>& rects) {
  ColorImage img(320, 240, 3);
  for (int y = 0; y < 240; ++y) {
    for (int x = 0; x < 320; ++x) {
      for (int c = 0; c < 3; ++c) img(x, y, c) = 128;
    }
  }
  for (const PixelRect& r : rects) {
    for (int y = r.y; y < r.y + r.h; ++y) {
      for (int x = r.x; x < r.x + r.w; ++x) {
        for (int c = 0; c < 3; ++c) img(x, y, c) = r.color[c];
      }
    }
  }
  return img;
}

// A detector's box around a person: a few pixels of margin.
track::Detection Box(const PixelRect& r) {
  track::Detection d;
  d.box = {r.x - 4.0, r.y - 4.0, r.w + 8.0, r.h + 8.0};
  d.score = 0.9;
  return d;
}

PeopleTrackerOptions Options(const std::string& backend, bool reid) {
  PeopleTrackerOptions options;
  options.mask_model.backend = infer::ParseMaskBackend(backend);
  options.mask_model.encoder = "tiny_" + backend + "_encoder";
  options.mask_model.decoder = "tiny_" + backend + "_decoder";
  options.mask_model.runtime.model_dir = semrec::testing::TinyModelDir();
  options.tracker.reid.enabled = reid;
  options.tracker.reid.tau = 0.5;
  options.tracker.reid.metric = track::ReidOptions::Metric::kCosine;
  return options;
}

class PeopleTrackerTest : public ::testing::TestWithParam<std::string> {};

// Red walks right, leaves for three frames, re-enters on the left; blue
// stands still. Returns the track ids of red before and after, of blue, and
// whether red's masks were right.
struct WalkResult {
  int red_before = 0, red_after = 0, blue = 0;
  bool red_reidentified = false;
};

WalkResult Walk(const std::string& backend, bool reid) {
  const auto registry =
      infer::ModelRegistry::Load(semrec::testing::TinyRegistryFile());
  PeopleTracker tracker(registry, Options(backend, reid));
  const PixelRect blue{220, 60, 40, 120, {0, 0, 255}};
  WalkResult result;
  for (int f = 0; f < 4; ++f) {
    const PixelRect red{20 + 10 * f, 80, 30, 100, {255, 0, 0}};
    const auto frame =
        tracker.Process(Scene({red, blue}), std::vector{Box(red), Box(blue)});
    EXPECT_EQ(frame.people.size(), 2u);
    if (frame.people.size() != 2) return result;
    // The box prompt finds exactly the person's rectangle.
    segment::Mask truth;
    truth.image_width = 320;
    truth.image_height = 240;
    truth.box = {red.x, red.y, red.x + red.w, red.y + red.h};
    truth.bits.assign(static_cast<size_t>(red.w) * red.h, 1);
    truth.area = red.w * red.h;
    EXPECT_GT(segment::MaskIoU(frame.people[0].mask, truth), 0.9);
    EXPECT_FALSE(frame.people[0].embedding.empty());
    result.red_before = frame.people[0].box.track_id;
    result.blue = frame.people[1].box.track_id;
  }
  for (int f = 0; f < 3; ++f) {
    const auto frame = tracker.Process(Scene({blue}), std::vector{Box(blue)});
    EXPECT_EQ(frame.people.at(0).box.track_id, result.blue);
  }
  const PixelRect red{100, 90, 30, 100, {255, 0, 0}};
  const auto frame =
      tracker.Process(Scene({red, blue}), std::vector{Box(red), Box(blue)});
  EXPECT_EQ(frame.people.at(1).box.track_id, result.blue);
  result.red_after = frame.people.at(0).box.track_id;
  result.red_reidentified = frame.people.at(0).box.reidentified;

  // A different person (green) entering is not taken for red or blue.
  const PixelRect green{20, 90, 30, 100, {0, 255, 0}};
  const auto next = tracker.Process(
      Scene({red, blue, green}), std::vector{Box(red), Box(blue), Box(green)});
  EXPECT_EQ(next.people.size(), 3u);
  EXPECT_NE(next.people.at(2).box.track_id, result.red_before);
  EXPECT_NE(next.people.at(2).box.track_id, result.blue);
  return result;
}

TEST_P(PeopleTrackerTest, ReidentifiesAReappearingPersonByAppearance) {
  const WalkResult with = Walk(GetParam(), true);
  EXPECT_NE(with.red_before, with.blue);
  EXPECT_EQ(with.red_after, with.red_before);
  EXPECT_TRUE(with.red_reidentified);
  const WalkResult without = Walk(GetParam(), false);
  EXPECT_NE(without.red_after, without.red_before);
  EXPECT_FALSE(without.red_reidentified);
}

INSTANTIATE_TEST_SUITE_P(Backends, PeopleTrackerTest,
                         ::testing::Values("sam", "sam2"));

TEST(PeopleTracker, InstanceMapAndOverlay) {
  PersonObservation a, b;
  a.box.track_id = 3;
  a.box.box = {10, 10, 20, 20};
  b.box.track_id = 7;
  b.box.box = {15, 15, 5, 5};  // in front of a: smaller, painted last
  const LabelMap map = PersonInstanceMap({a, b}, 64, 48);
  EXPECT_EQ(map(12, 12), 3);
  EXPECT_EQ(map(17, 17), 7);
  EXPECT_EQ(map(40, 40), 0);
  EXPECT_EQ(map(29, 29), 3);
  EXPECT_EQ(map(30, 30), 0);
  const ColorImage rgb = Scene({});
  const ColorImage overlay = RenderPeopleOverlay(rgb, {a, b});
  EXPECT_EQ(overlay.width(), rgb.width());
  EXPECT_NE(overlay(12, 12, 0) + overlay(12, 12, 1) + overlay(12, 12, 2),
            3 * 128);
}

TEST(PeopleTracker, BoxesOnlyWithoutMasksAndBadOptions) {
  PeopleTrackerOptions options;
  options.masks = false;
  const auto registry =
      infer::ModelRegistry::Load(semrec::testing::TinyRegistryFile());
  PeopleTracker tracker(registry, options);
  const PixelRect red{20, 80, 30, 100, {255, 0, 0}};
  const auto frame = tracker.Process(Scene({red}), std::vector{Box(red)});
  ASSERT_EQ(frame.people.size(), 1u);
  EXPECT_EQ(frame.people[0].mask.area, 0);
  EXPECT_TRUE(frame.people[0].embedding.empty());
  options.embedding = "colour";
  EXPECT_THROW(PeopleTracker(registry, options), InvalidArgument);
}

}  // namespace
}  // namespace semrec::pipeline
