// `semrec eval traj EST GT`: trajectory accuracy (ATE after rigid alignment,
// RPE) of estimated camera poses against ground truth.
#include <cstdio>

#include "commands.h"
#include "semrec/eval/trajectory.h"
#include "semrec/io/pose_io.h"
#include "semrec/io/sequence_reader.h"

namespace semrec::cli {
namespace {

struct TrajArgs {
  std::string estimate;
  std::string ground_truth;
  std::string pose_correction;
  eval::TrajectoryOptions options;
  bool json = false;
};

io::SequenceReaderOptions GroundTruthOptions(const TrajArgs& args) {
  io::SequenceReaderOptions options;
  options.pose_correction_path = args.pose_correction;
  return options;
}

void RunTraj(const TrajArgs& args) {
  args.options.Check();
  const eval::TrajectoryErrors e = eval::EvaluateTrajectory(
      io::ReadTumTrajectory(args.estimate),
      eval::ReadTrajectory(args.ground_truth, GroundTruthOptions(args)),
      args.options);
  if (!args.json) {
    std::printf("%s", eval::TrajectoryErrorsText(e).c_str());
    return;
  }
  std::printf("%s\n", eval::TrajectoryErrorsJson(e).dump(2).c_str());
}

}  // namespace

void AddEvalTraj(CLI::App* eval) {
  auto args = std::make_shared<TrajArgs>();
  CLI::App* cmd = eval->add_subcommand(
      "traj",
      "Camera trajectory accuracy as the TUM RGB-D benchmark measures it: "
      "poses associated by timestamp, the estimate rigidly aligned to the "
      "ground truth (no scale), then ATE (RMSE, mean, median, max of the "
      "position errors) and RPE (the error of the motion between poses "
      "--delta apart, RMSE and per metre travelled).");
  cmd->add_option("estimate", args->estimate,
                  "Estimated poses (TUM: 'timestamp tx ty tz qx qy qz qw')")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("ground_truth", args->ground_truth,
                  "Ground truth: a TUM file or a sequence (its poses)")
      ->required()
      ->check(CLI::ExistingPath);
  cmd->add_option("--pose-correction", args->pose_correction,
                  "The sequence's pose correction (YAML), as for run")
      ->check(CLI::ExistingFile);
  cmd->add_option("--max-dt", args->options.max_time_difference_s,
                  "Pair poses at most this far apart in time (s)")
      ->capture_default_str();
  cmd->add_option("--delta", args->options.rpe_delta_frames,
                  "RPE between poses this many pairs apart")
      ->capture_default_str();
  cmd->add_flag("--json", args->json, "Print JSON");
  cmd->callback([args] { RunTraj(*args); });
}

}  // namespace semrec::cli
