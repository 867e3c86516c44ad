#include "semrec/tasks/track_task.h"

#include <map>
#include <set>

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/io/mot_io.h"
#include "semrec/testing/test_util.h"

namespace semrec::tasks {
namespace {

// Two people walking towards each other on MOTChallenge detections (ids
// unknown, -1): the task's tracks follow each person with one id, frame by
// frame, and the result file holds every detection once.
TEST(TrackTask, DetectionsAloneGiveOneTrackPerPerson) {
  testing::TempDir dir;
  std::vector<io::MotBox> detections;
  for (int f = 1; f <= 12; ++f) {
    detections.push_back({f, -1, 10.0 + 8.0 * f, 50.0, 40.0, 100.0, 0.9});
    detections.push_back({f, -1, 400.0 - 8.0 * f, 60.0, 40.0, 100.0, 0.9});
  }
  io::WriteMotFile(dir / "det.txt", detections);
  TrackTaskOptions options;
  options.detections = dir / "det.txt";
  options.out = dir / "result.txt";
  options.people.tracker = track::TrackerOptions::Paper();
  options.offline = track::OfflineOptions();
  const TrackTaskResult r = RunTrackTask(nullptr, options);
  EXPECT_EQ(r.frames, 12u);
  EXPECT_EQ(r.detections, 24u);
  const std::vector<io::MotBox> result = io::ReadMotFile(options.out);
  EXPECT_EQ(result.size(), r.boxes);
  std::map<int, std::set<int>> ids_left_of_middle, ids_right_of_middle;
  for (const io::MotBox& b : result) {
    // Until they meet the left person is left of x = 200.
    if (b.frame > 10) continue;
    (b.left < 200.0 ? ids_left_of_middle : ids_right_of_middle)[b.id].insert(
        b.frame);
  }
  ASSERT_EQ(ids_left_of_middle.size(), 1u);
  ASSERT_EQ(ids_right_of_middle.size(), 1u);
  EXPECT_NE(ids_left_of_middle.begin()->first,
            ids_right_of_middle.begin()->first);
  EXPECT_GE(ids_left_of_middle.begin()->second.size(), 8u);
}

TEST(TrackTask, BadOptionsAreRefusedBeforeAnyWork) {
  TrackTaskOptions options;
  options.out = "/tmp/never";
  EXPECT_THROW(RunTrackTask(nullptr, options), InvalidArgument);  // no input
  options.detections = "/no/such/det.txt";
  options.pca_dims = 0;
  EXPECT_THROW(RunTrackTask(nullptr, options), InvalidArgument);
  options.pca_dims = 3;
  EXPECT_THROW(RunTrackTask(nullptr, options), IoError);  // missing file
  options.input = "/no/such/images";
  options.people.masks = false;
  options.fit_pca = "/tmp/pca.json";
  EXPECT_THROW(RunTrackTask(nullptr, options), InvalidArgument);
}

}  // namespace
}  // namespace semrec::tasks
