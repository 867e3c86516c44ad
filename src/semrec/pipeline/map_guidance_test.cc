#include "semrec/pipeline/map_guidance.h"

#include <gtest/gtest.h>

#include "semrec/core/error.h"

namespace semrec::pipeline {
namespace {

using fuse::ProjectedMap;

// A 200 x 100 frame: all explained except `blob` (unexplained) and `specks`
// 1-pixel holes; the bottom 10 rows have no depth.
ProjectedMap Projected(int blob_x0, int blob_x1, bool specks) {
  ProjectedMap p;
  p.state = Image<uint8_t>(200, 100, 1, ProjectedMap::kExplained);
  for (int y = 90; y < 100; ++y) {
    for (int x = 0; x < 200; ++x) p.state(x, y) = ProjectedMap::kNoDepth;
  }
  for (int y = 20; y < 60; ++y) {
    for (int x = blob_x0; x < blob_x1; ++x) {
      p.state(x, y) = ProjectedMap::kUnexplained;
    }
  }
  if (specks) {
    for (int x = 5; x < 200; x += 20) {
      p.state(x, 5) = ProjectedMap::kContradicted;
    }
  }
  p.valid_depth_pixels = size_t{200} * 90;
  return p;
}

Transform Moved(double dx, double angle_deg) {
  return Transform(
      Eigen::AngleAxisd(angle_deg * M_PI / 180.0, Eigen::Vector3d::UnitY())
          .toRotationMatrix(),
      Eigen::Vector3d(dx, 0, 0));
}

TEST(MapGuidance, PromptsOnlyWhereNewContentIsAndSkipsExplainedFrames) {
  MapGuidanceOptions options;
  options.min_region_px = 50;
  options.region_margin_px = 3;
  // A 40 x 40 unexplained blob (a new object): partial, prompts on it and a
  // 3-pixel margin; the specks are noise.
  const GuidanceDecision d = DecideFrame(
      Projected(100, 140, true), Moved(0.1, 5), Transform(), 3, options);
  EXPECT_EQ(d.mode, FrameMode::kPartial);
  EXPECT_EQ(d.reason, GuidanceReason::kNewContent);
  EXPECT_NEAR(d.unexplained_share, 1600.0 / (200 * 90), 1e-12);
  size_t region_px = 0;
  for (uint8_t v : d.prompt_region.values()) region_px += v;
  EXPECT_EQ(region_px, 46u * 46u);
  EXPECT_EQ(d.prompt_region(120, 40), 1);
  EXPECT_EQ(d.prompt_region(97, 17), 1);  // in the margin
  EXPECT_EQ(d.prompt_region(96, 40), 0);
  EXPECT_EQ(d.prompt_region(5, 5), 0);  // a speck
  // The blob is a tracked person (their id map): theirs, not prompted.
  LabelMap person(200, 100);
  for (int y = 20; y < 60; ++y) {
    for (int x = 100; x < 140; ++x) person(x, y) = 3;
  }
  EXPECT_EQ(DecideFrame(Projected(100, 140, true), Moved(0.1, 5), Transform(),
                        3, options, &person)
                .mode,
            FrameMode::kProjectionOnly);
  const LabelMap wrong_size(10, 10);
  EXPECT_THROW(DecideFrame(Projected(100, 140, true), Moved(0.1, 5),
                           Transform(), 3, options, &wrong_size),
               InvalidArgument);
  // A tiny blob only: explained enough to skip the models.
  const GuidanceDecision quiet = DecideFrame(
      Projected(100, 101, true), Moved(0.1, 5), Transform(), 3, options);
  EXPECT_EQ(quiet.mode, FrameMode::kProjectionOnly);
  EXPECT_EQ(quiet.unexplained_share, 0.0);
  for (uint8_t v : quiet.prompt_region.values()) ASSERT_EQ(v, 0);
  // A blob of 10% of the frame under a 15% threshold: also projection only.
  options.projection_only_below = 0.15;
  EXPECT_EQ(DecideFrame(Projected(100, 140, false), Transform(), Transform(), 1,
                        options)
                .mode,
            FrameMode::kProjectionOnly);
}

TEST(MapGuidance, DisagreementWithTheSemanticBranchIsPromptedAndWins) {
  MapGuidanceOptions options;
  options.min_region_px = 50;
  options.region_margin_px = 2;
  options.prompt_on_disagreement = true;
  ProjectedMap p = Projected(0, 0, false);  // all explained ...
  p.class_id = LabelMap(200, 100, 1, 5);    // ... as class 5
  p.object_id = Image<uint32_t>(200, 100, 1, 9);
  // The semantic branch says 7 on a 30 x 30 block, on a 2-pixel band (a
  // blurred border) and on specks.
  LabelMap semantic(200, 100, 1, 5);
  for (int y = 10; y < 40; ++y) {
    for (int x = 20; x < 50; ++x) semantic(x, y) = 7;
  }
  for (int x = 60; x < 190; ++x) semantic(x, 70) = semantic(x, 71) = 7;
  for (int x = 5; x < 200; x += 20) semantic(x, 5) = 7;
  GuidanceDecision d = DecideFrame(p, Transform(), Transform(), 1, options);
  ASSERT_EQ(d.mode, FrameMode::kProjectionOnly);
  const double share = AddDisagreement(p, semantic, options, &d);
  EXPECT_NEAR(share, 900.0 / (200 * 90), 1e-12);
  EXPECT_EQ(d.mode, FrameMode::kPartial);
  EXPECT_EQ(d.reason, GuidanceReason::kDisagreement);
  size_t region_px = 0;
  for (uint8_t v : d.prompt_region.values()) region_px += v;
  EXPECT_EQ(region_px, 34u * 34u);  // the block and its margin only
  EXPECT_EQ(d.override_region(30, 20), 1);
  EXPECT_EQ(d.override_region(100, 70), 0);  // the band
  // The fresh segmentation wins there over the projection; elsewhere the map.
  segment::VoteResult fresh;
  fresh.instance = LabelMap(200, 100, 1, 1);
  fresh.semantic = semantic;
  const fuse::FrameLabels l = ComposeFrameLabels(p, d, &fresh, "f");
  EXPECT_EQ(l.semantic(30, 20), 7);
  EXPECT_EQ(l.instance(30, 20), 1);
  EXPECT_EQ(l.semantic(100, 70), 5);
  EXPECT_EQ(l.semantic(5, 5), 5);
  // Full frames are left alone; without disagreement nothing changes.
  GuidanceDecision full = DecideFrame(p, Transform(), std::nullopt, 0, options);
  EXPECT_EQ(AddDisagreement(p, semantic, options, &full), 0.0);
  EXPECT_TRUE(full.override_region.empty());
  GuidanceDecision quiet = DecideFrame(p, Transform(), Transform(), 1, options);
  EXPECT_EQ(AddDisagreement(p, LabelMap(200, 100, 1, 5), options, &quiet), 0.0);
  EXPECT_EQ(quiet.mode, FrameMode::kProjectionOnly);
}

TEST(MapGuidance, DriftGuardForcesFullFrames) {
  MapGuidanceOptions options;
  const ProjectedMap explained = Projected(0, 0, false);
  const auto decide = [&](const std::optional<Transform>& last, size_t since,
                          const Transform& now) {
    return DecideFrame(explained, now, last, since, options);
  };
  EXPECT_EQ(decide(std::nullopt, 0, Transform()).reason,
            GuidanceReason::kFirstFrame);
  EXPECT_EQ(decide(Transform(), 10, Transform()).reason,
            GuidanceReason::kRefresh);
  EXPECT_EQ(decide(Transform(), 9, Transform()).mode,
            FrameMode::kProjectionOnly);
  EXPECT_EQ(decide(Transform(), 1, Moved(0.0, 30)).reason,
            GuidanceReason::kCameraMoved);
  EXPECT_EQ(decide(Transform(), 1, Moved(0.8, 0)).reason,
            GuidanceReason::kCameraMoved);
  EXPECT_EQ(decide(Moved(0.5, 30), 1, Moved(0.8, 0)).mode,
            FrameMode::kFull);  // turned back 30 degrees
  EXPECT_EQ(decide(Moved(0.5, 10), 1, Moved(0.8, 0)).mode,
            FrameMode::kProjectionOnly);
  const GuidanceDecision full = decide(std::nullopt, 0, Transform());
  for (uint8_t v : full.prompt_region.values()) ASSERT_EQ(v, 1);
  EXPECT_STREQ(FrameModeName(FrameMode::kPartial), "partial");

  options.refresh_every = 0;
  EXPECT_THROW(options.Check(), InvalidArgument);
  options = {};
  options.projection_only_below = 1.5;
  EXPECT_THROW(options.Check(), InvalidArgument);
}

}  // namespace
}  // namespace semrec::pipeline
