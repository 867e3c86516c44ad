#include "semrec/tasks/run_task.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/eval/scene_result.h"
#include "semrec/eval/trajectory.h"
#include "semrec/io/pose_io.h"
#include "semrec/testing/small_scene.h"
#include "semrec/testing/test_util.h"

namespace semrec::tasks {
namespace {

using testing::QuietProgress;

// The task is the library's run: from given labels it writes what
// RunSequence writes (the same scene, byte for byte) and a report.html
// listing every object of report.json.
TEST(RunTask, GivenLabelsRunAsRunSequenceWithItsReport) {
  testing::TempDir dir;
  synth::WriteSyntheticSequence(testing::SmallScene("six-objects", 6),
                                dir / "seq", QuietProgress());
  RunTaskOptions task;
  task.sequence = dir / "seq";
  task.out = dir / "task";
  task.labels = fuse::LabelSpec::Parse("gt");
  task.run.config_text = "labels: gt\n";
  task.report_pictures = false;
  const RunTaskResult result = RunTask(task, QuietProgress());

  pipeline::RunOptions direct = task.run;
  direct.pipeline.labels = pipeline::ScenePipelineOptions::Labels::kGiven;
  direct.given_labels = fuse::LabelSpec::Parse("gt");
  const pipeline::RunResult reference =
      pipeline::RunSequence(io::SequenceReader::Open(dir / "seq"), nullptr,
                            direct, dir / "direct", QuietProgress());
  EXPECT_EQ(ReadTextFile(dir / "task" / "static.usda"),
            ReadTextFile(dir / "direct" / "static.usda"));
  EXPECT_EQ(result.run.report.objects, reference.report.objects);
  EXPECT_GE(result.run.report.objects, 5u);

  ASSERT_TRUE(result.report.has_value());
  EXPECT_EQ(result.report->pictures, 0);
  const std::string html = ReadTextFile(dir / "task" / "report.html");
  size_t rows = 0;
  for (size_t at = html.find("<tr><td class=\"num\">"); at != std::string::npos;
       at = html.find("<tr><td class=\"num\">", at + 1)) {
    ++rows;
  }
  EXPECT_EQ(rows, result.run.report.scene.size());

  // `semrec eval scene` on the task's scene: the ground-truth labels' scene
  // scores near perfect, and the printed summary says what the JSON says.
  eval::SceneResultOptions scored;
  scored.result = dir / "task";
  scored.gt = dir / "seq" / "gt" / "surface_points.ply";
  scored.observed_in = dir / "seq";
  const eval::SceneResultEvaluation e = eval::EvaluateSceneResult(scored);
  EXPECT_GT(e.metrics.ap50, 0.9);
  const std::string text = e.Text(scored, /*per_object=*/true);
  EXPECT_NE(text.find(fmt::format("AP50 {:.2f}", 100 * e.metrics.ap50)),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("where each ground-truth object's points went"),
            std::string::npos);
  EXPECT_EQ(e.Text(scored, false).find("where each ground-truth object"),
            std::string::npos);
}

// Poses estimated in the run: the scene, brought into the ground truth's
// frame by the estimate's alignment, scores as the run with the true poses
// does; the report and poses.txt say what was estimated.
TEST(RunTask, EstimatedPosesGiveTheSceneOfTheTrueOnes) {
  testing::TempDir dir;
  synth::WriteSyntheticSequence(testing::SmallScene("office", 20), dir / "seq",
                                QuietProgress());
  RunTaskOptions task;
  task.sequence = dir / "seq";
  task.labels = fuse::LabelSpec::Parse("gt");
  task.report_html = false;
  const auto score = [&](const std::filesystem::path& out) {
    eval::SceneResultOptions scored;
    scored.result = out;
    scored.gt = dir / "seq" / "gt" / "surface_points.ply";
    scored.observed_in = dir / "seq";
    scored.gt_trajectory = dir / "seq";
    return eval::EvaluateSceneResult(scored).metrics;
  };
  task.out = dir / "true";
  task.run.poses = pipeline::RunOptions::Poses::kAuto;  // the recording's
  const RunTaskResult truth = RunTask(task, QuietProgress());
  EXPECT_EQ(truth.run.report.poses.source, "file");
  EXPECT_FALSE(std::filesystem::exists(dir / "true" / "poses.txt"));
  task.out = dir / "estimated";
  task.run.poses = pipeline::RunOptions::Poses::kEstimate;
  const RunTaskResult estimated = RunTask(task, QuietProgress());
  const pipeline::PoseReport& poses = estimated.run.report.poses;
  EXPECT_EQ(poses.source, "estimated");
  EXPECT_EQ(poses.frames.size(), 20u);
  EXPECT_EQ(poses.lost_frames, 0u);
  EXPECT_GE(poses.keyframes, 1u);
  const pipeline::RunReport read =
      pipeline::ReadRunReport(dir / "estimated" / "report.json");
  EXPECT_EQ(read.poses.frames.size(), 20u);
  EXPECT_EQ(read.poses.method, poses.method);
  const eval::TrajectoryErrors errors = eval::EvaluateTrajectory(
      io::ReadTumTrajectory(dir / "estimated" / "poses.txt"),
      eval::ReadTrajectory(dir / "seq"));
  EXPECT_LT(errors.ate_rmse_m, 0.01);
  const eval::SceneMetrics a = score(dir / "true"),
                           b = score(dir / "estimated");
  EXPECT_GT(a.ap50, 0.7);
  EXPECT_NEAR(b.ap50, a.ap50, 0.05);
  EXPECT_NEAR(b.mean_iou, a.mean_iou, 0.03);
  EXPECT_EQ(estimated.run.report.objects, truth.run.report.objects);
  // The estimate's scene is not scored without its alignment.
  eval::SceneResultOptions unaligned;
  unaligned.result = dir / "estimated";
  unaligned.gt = dir / "seq" / "gt" / "surface_points.ply";
  EXPECT_THROW(eval::EvaluateSceneResult(unaligned), InvalidArgument);
}

TEST(RunTask, ModelChoiceSetsTheSegmenterAndThePeopleTracker) {
  ModelChoice choice;
  choice.masks = "none";
  choice.object_detector = "yolox_nano";
  // The detector's boxes prompt masks: without masks it cannot run.
  EXPECT_THROW(choice.Check(), InvalidArgument);
  choice.object_detector.clear();
  choice.semantic = "deeplab_v3";
  choice.people_score = 0.5f;
  choice.runtime.intra_op_threads = 1;
  pipeline::ScenePipelineOptions pipeline;
  pipeline.labels = pipeline::ScenePipelineOptions::Labels::kGiven;
  ApplyModelChoice(infer::ModelRegistry(), choice, &pipeline);
  EXPECT_EQ(pipeline.labels, pipeline::ScenePipelineOptions::Labels::kModels);
  EXPECT_EQ(pipeline.segmenter.semantic.model, "deeplab_v3");
  EXPECT_EQ(pipeline.segmenter.semantic.runtime.intra_op_threads, 1);
  EXPECT_FALSE(pipeline.segmenter.use_masks);
  EXPECT_FALSE(pipeline.segmenter.objects.enabled());
  EXPECT_FALSE(pipeline.people.masks);
  EXPECT_FLOAT_EQ(pipeline.people.detector.score_threshold, 0.5f);
  EXPECT_EQ(pipeline.people.detector.runtime.intra_op_threads, 1);
}

TEST(RunTask, BadOptionsAndInputsAreRefusedWithTheirReason) {
  testing::TempDir dir;
  RunTaskOptions task;
  task.sequence = dir / "missing";
  task.out = dir / "out";
  task.labels = fuse::LabelSpec::Parse("gt");
  task.run.pipeline.map_guidance = true;
  try {
    RunTask(task);
    ADD_FAILURE() << "map guidance without the models ran";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("map guidance"), std::string::npos)
        << e.what();
  }
  task.run.pipeline.map_guidance = false;
  try {
    RunTask(task);
    ADD_FAILURE() << "a missing recording ran";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace semrec::tasks
