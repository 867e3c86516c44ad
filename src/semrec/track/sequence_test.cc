#include "semrec/track/sequence.h"

#include <set>

#include <gtest/gtest.h>

#include "semrec/core/error.h"

namespace semrec::track {
namespace {

// One person walking right 10 px per frame, seen in the given frames.
std::map<int, std::vector<Detection>> Walk(const std::vector<int>& frames,
                                           double top = 100.0) {
  std::map<int, std::vector<Detection>> by_frame;
  for (int f : frames) {
    by_frame[f].push_back({{10.0 * f, top, 40.0, 100.0}, 0.9, {}});
  }
  return by_frame;
}

TrackerOptions Lenient() {
  TrackerOptions o = TrackerOptions::Improved();
  o.motion = TrackerOptions::Motion::kVelocity;
  return o;
}

TEST(TrackSequence, EqualsFrameByFrameUpdates) {
  auto by_frame = Walk({1, 2, 3, 5, 6});
  for (auto& [f, d] : Walk({2, 3, 4}, 400.0)) by_frame[f].push_back(d[0]);
  Tracker a(Lenient()), b(Lenient());
  int ticks = 0;
  const auto points = TrackSequence(&a, by_frame, 7, [&] { ++ticks; });
  EXPECT_EQ(ticks, 7);
  size_t k = 0;
  for (int f = 1; f <= 7; ++f) {
    const auto it = by_frame.find(f);
    for (const TrackedBox& t : b.Update(
             it == by_frame.end() ? std::vector<Detection>{} : it->second)) {
      ASSERT_LT(k, points.size());
      EXPECT_EQ(points[k].frame, f);
      EXPECT_EQ(points[k].box.track_id, t.track_id);
      EXPECT_DOUBLE_EQ(points[k].box.box.left, t.box.left);
      ++k;
    }
  }
  EXPECT_EQ(k, points.size());
  EXPECT_EQ(k, 8u);
}

TEST(FinishTracks, OffKeepsConfirmedBoxesOnly) {
  TrackerOptions o = Lenient();
  o.min_hits = 3;
  Tracker tracker(o);
  // A long track and a two-frame one that never reaches min_hits.
  auto by_frame = Walk({1, 2, 3, 4, 5});
  for (auto& [f, d] : Walk({2, 3}, 400.0)) by_frame[f].push_back(d[0]);
  const auto points = TrackSequence(&tracker, by_frame, 5);
  ASSERT_EQ(points.size(), 7u);
  const auto out = FinishTracks(points, OfflineOptions{});
  ASSERT_EQ(out.size(), 3u);  // frames 3-5 of the long track
  EXPECT_EQ(out[0].frame, 3);
  EXPECT_EQ(out[2].frame, 5);

  OfflineOptions backfill;
  backfill.backfill_tentative = true;
  const auto all = FinishTracks(points, backfill);
  ASSERT_EQ(all.size(), 5u);  // the short track stays out
  for (size_t k = 0; k < all.size(); ++k) {
    EXPECT_EQ(all[k].frame, static_cast<int>(k) + 1);
    EXPECT_TRUE(all[k].box.confirmed);
    EXPECT_FALSE(all[k].interpolated);
  }
}

TEST(FinishTracks, InterpolatesGapsUpToTheLimit) {
  Tracker tracker(Lenient());
  // Gaps: frames 3-4 (2 frames), frames 8-11 (4 frames).
  const auto points =
      TrackSequence(&tracker, Walk({1, 2, 5, 6, 7, 12, 13}), 13);
  std::set<int> ids;
  for (const auto& p : points) ids.insert(p.box.track_id);
  ASSERT_EQ(ids.size(), 1u) << "the walker must keep one id across the gaps";

  OfflineOptions o;
  o.max_gap_frames = 2;
  auto out = FinishTracks(points, o);
  ASSERT_EQ(out.size(), 9u);  // 7 observed + 2 filled
  for (const auto& p : out) {
    const bool filled = p.frame == 3 || p.frame == 4;
    EXPECT_EQ(p.interpolated, filled) << p.frame;
    // The walk is linear, so the filled boxes lie exactly on it.
    EXPECT_NEAR(p.box.box.left, 10.0 * p.frame, 1e-9) << p.frame;
    EXPECT_NEAR(p.box.box.top, 100.0, 1e-9);
  }
  o.max_gap_frames = 4;
  out = FinishTracks(points, o);
  ASSERT_EQ(out.size(), 13u);
  for (size_t k = 0; k < out.size(); ++k) {
    EXPECT_EQ(out[k].frame, static_cast<int>(k) + 1);
    EXPECT_NEAR(out[k].box.box.left, 10.0 * out[k].frame, 1e-9);
  }
}

TEST(FinishTracks, NoFillingAcrossReidentificationOrFromUnreportedBoxes) {
  // Hand-made points: track 1 seen in frames 1-2, re-identified in frame 5.
  std::vector<TrackPoint> points;
  for (int f : {1, 2, 5}) {
    TrackPoint p;
    p.frame = f;
    p.box.track_id = 1;
    p.box.box = {10.0 * f, 0, 10, 10};
    p.box.reidentified = f == 5;
    points.push_back(p);
  }
  OfflineOptions o;
  o.max_gap_frames = 10;
  EXPECT_EQ(FinishTracks(points, o).size(), 3u);
  points[2].box.reidentified = false;
  EXPECT_EQ(FinishTracks(points, o).size(), 5u);
  // Frame 2 tentative and not backfilled: the fill starts at frame 1.
  points[1].box.confirmed = false;
  const auto out = FinishTracks(points, o);
  ASSERT_EQ(out.size(), 5u);
  EXPECT_TRUE(out[1].interpolated);
  EXPECT_NEAR(out[1].box.box.left, 20.0, 1e-9);
}

TEST(FinishTracks, DropsShortTracksCountingObservedFramesOnly) {
  Tracker tracker(Lenient());
  auto by_frame = Walk({1, 2, 3, 4});
  // Seen in frames 2 and 6 only: 2 observations, 3 filled frames between.
  for (auto& [f, d] : Walk({2, 6}, 400.0)) by_frame[f].push_back(d[0]);
  by_frame[6].back().box.left = 20.0 + 4.0;  // close enough to match
  const auto points = TrackSequence(&tracker, by_frame, 6);
  OfflineOptions o;
  o.max_gap_frames = 10;
  o.min_track_frames = 3;
  const auto out = FinishTracks(points, o);
  ASSERT_EQ(out.size(), 4u);
  for (const auto& p : out) EXPECT_EQ(p.box.box.top, 100.0);
  o.min_track_frames = 2;
  EXPECT_EQ(FinishTracks(points, o).size(), 9u);
}

TEST(FinishTracks, SortedByFrameThenId) {
  Tracker tracker(Lenient());
  auto by_frame = Walk({1, 2, 3});
  for (auto& [f, d] : Walk({1, 2, 3}, 400.0))
    by_frame[f].insert(by_frame[f].begin(), d[0]);
  const auto out =
      FinishTracks(TrackSequence(&tracker, by_frame, 3), OfflineOptions{});
  ASSERT_EQ(out.size(), 6u);
  for (size_t k = 1; k < out.size(); ++k) {
    EXPECT_TRUE(out[k - 1].frame < out[k].frame ||
                (out[k - 1].frame == out[k].frame &&
                 out[k - 1].box.track_id < out[k].box.track_id));
  }
}

TEST(OfflineOptions, CheckAndPresets) {
  OfflineOptions o;
  EXPECT_TRUE(o.Off());
  o.max_gap_frames = -1;
  EXPECT_THROW(o.Check(), InvalidArgument);
  o = OfflineOptions{};
  o.min_track_frames = 0;
  EXPECT_THROW(o.Check(), InvalidArgument);
  EXPECT_THROW(FinishTracks({}, o), InvalidArgument);
  EXPECT_FALSE(OfflineOptions::Improved().Off());
  EXPECT_NO_THROW(OfflineOptions::Improved().Check());
}

}  // namespace
}  // namespace semrec::track
