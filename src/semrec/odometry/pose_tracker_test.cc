#include "semrec/odometry/pose_tracker.h"

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "semrec/eval/trajectory.h"
#include "semrec/io/image_io.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/testing/small_scene.h"
#include "semrec/testing/test_util.h"

namespace semrec::odometry {
namespace {

struct Tracked {
  eval::TrajectoryErrors errors;
  /// Tracking stopped (TrackingLost) before the end.
  bool stopped = false;
  size_t lost = 0;
  double max_masked_share = 0.0;
};

// Tracks every frame of a synthetic sequence and scores the estimate
// against the sequence's exact poses.
Tracked TrackSequence(const io::SequenceReader& reader,
                      const PoseTrackerOptions& options, bool mask_people) {
  PoseTracker tracker(options, reader.intrinsics());
  std::vector<io::StampedPose> estimate, truth;
  Tracked out;
  for (size_t i = 0; i < reader.size(); ++i) {
    const Frame frame = reader.Read(i);
    std::optional<LabelMap> people;
    const auto& layers = reader.index().frames[i].layers;
    if (mask_people && layers.contains("person")) {
      people = io::ReadLabelImage(layers.at("person"));
    }
    PoseTrackResult r;
    try {
      r = tracker.Track(frame, people ? &*people : nullptr);
    } catch (const TrackingLost&) {
      out.stopped = true;
      return out;
    }
    out.max_masked_share =
        std::max(out.max_masked_share,
                 static_cast<double>(r.masked_pixels) /
                     static_cast<double>(frame.depth.NumPixels()));
    estimate.push_back({frame.timestamp_s, r.T_world_camera});
    truth.push_back({frame.timestamp_s, frame.T_world_camera});
  }
  out.errors = eval::EvaluateTrajectory(estimate, truth);
  out.lost = tracker.lost_frames();
  return out;
}

TEST(PoseTracker, FollowsAHandHeldOrbitWithinACentimetre) {
  semrec::testing::TempDir dir;
  synth::WriteSyntheticSequence(semrec::testing::SmallScene("office", 30),
                                dir.path(), semrec::testing::QuietProgress());
  const io::SequenceReader reader = io::SequenceReader::Open(dir.path());
  for (const auto method : {PoseTrackerOptions::Method::kFrameToKeyframe,
                            PoseTrackerOptions::Method::kFrameToFrame}) {
    PoseTrackerOptions options;
    options.method = method;
    const Tracked t = TrackSequence(reader, options, false);
    EXPECT_EQ(t.lost, 0u) << MethodName(method);
    EXPECT_GT(t.errors.path_length_m, 0.3) << "the camera moves";
    EXPECT_LT(t.errors.ate_rmse_m, 0.01) << MethodName(method);
  }
}

TEST(PoseTracker, PeopleLeftOutDoNotDragAStillCamera) {
  // A hand-held camera standing still while three people walk through the
  // view. Frame-to-frame photometric tracking follows the people when it
  // sees them (it loses the room, or drifts tens of centimetres) and the
  // room when they are masked.
  semrec::testing::TempDir dir;
  // Full VGA: at 320 x 240 the people cover too much of the little texture.
  synth::SynthOptions scene = semrec::testing::SmallScene("people", 20);
  scene.width = 640;
  scene.height = 480;
  scene.fx = scene.fy = 525.0;
  synth::WriteSyntheticSequence(scene, dir.path(),
                                semrec::testing::QuietProgress());
  const io::SequenceReader reader = io::SequenceReader::Open(dir.path());
  PoseTrackerOptions options;
  options.method = PoseTrackerOptions::Method::kFrameToFrame;
  options.loss = PoseTrackerOptions::Loss::kPhotometric;
  options.image_downsampling = 1;
  const Tracked seen = TrackSequence(reader, options, false);
  const Tracked masked = TrackSequence(reader, options, true);
  EXPECT_GT(masked.max_masked_share, 0.02) << "people are in view";
  EXPECT_EQ(masked.lost, 0u);
  EXPECT_LT(masked.errors.ate_rmse_m, 0.02);
  EXPECT_FALSE(masked.stopped);
  EXPECT_TRUE(seen.stopped ||
              seen.errors.ate_rmse_m > 3.0 * masked.errors.ate_rmse_m)
      << "unmasked: " << seen.errors.ate_rmse_m << " m";
}

TEST(PoseTracker, FramesWithoutDepthAreLostThenTrackingStops) {
  semrec::testing::TempDir dir;
  synth::WriteSyntheticSequence(semrec::testing::SmallScene("office", 3),
                                dir.path(), semrec::testing::QuietProgress());
  const io::SequenceReader reader = io::SequenceReader::Open(dir.path());
  PoseTrackerOptions options;
  options.max_lost_frames = 2;
  PoseTracker tracker(options, reader.intrinsics());
  const Frame first = reader.Read(0);
  EXPECT_TRUE(tracker.Track(first).tracked);
  Frame blank = reader.Read(1);
  std::fill(blank.depth.values().begin(), blank.depth.values().end(), 0.0f);
  const PoseTrackResult lost = tracker.Track(blank);
  EXPECT_FALSE(lost.tracked);
  EXPECT_FALSE(lost.lost_reason.empty());
  EXPECT_TRUE(lost.T_world_camera.IsApprox(Transform(), 1e-9))
      << "a lost frame keeps the last pose";
  try {
    tracker.Track(blank);
    FAIL() << "no TrackingLost";
  } catch (const TrackingLost& e) {
    EXPECT_NE(std::string(e.what()).find("2 frames in a row"),
              std::string::npos)
        << e.what();
  }
}

TEST(PoseTracker, RefusesBadOptionsAndFramesOfAnotherSize) {
  PoseTrackerOptions o;
  EXPECT_NO_THROW(o.Check());
  o.cloud_voxel_m = 0.0;
  EXPECT_THROW(o.Check(), InvalidArgument);
  EXPECT_EQ(ParseMethod("frame-to-frame"),
            PoseTrackerOptions::Method::kFrameToFrame);
  EXPECT_THROW(ParseMethod("icp"), InvalidArgument);
  const CameraIntrinsics k{64, 48, 50.0, 50.0, 32.0, 24.0};
  PoseTracker tracker({}, k);
  Frame frame;
  frame.color = ColorImage(32, 24, 3);
  frame.depth = DepthImage(32, 24);
  EXPECT_THROW(tracker.Track(frame), InvalidArgument);
}

}  // namespace
}  // namespace semrec::odometry
