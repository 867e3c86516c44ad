// Subcommands of the `semrec` CLI. Each Register* adds its CLI11 subcommand and
// the callback that runs it; callbacks throw semrec::Error on bad input, which
// main() turns into "error: ..." + exit 1, and UsageError for an invalid
// command line (exit 2).
#pragma once

#include <cstdlib>
#include <set>
#include <string>

#include <CLI/CLI.hpp>

#include "semrec/core/error.h"
#include "semrec/infer/model_registry.h"
#include "semrec/infer/onnx_model.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/pipeline/run_sequence.h"
#include "semrec/segment/detector_votes.h"

namespace semrec::cli {

/// The command line asks for something invalid (an option value out of
/// range, a missing input): main() prints it and exits with 2, like CLI11's
/// own parse errors.
class UsageError : public Error {
 public:
  using Error::Error;
};

/// Throws UsageError(message) unless `ok`.
inline void CheckUsage(bool ok, const std::string& message) {
  if (!ok) throw UsageError(message);
}

/// CLI11 check: a positive power of 2 (e.g. --dense-stride).
inline std::string PowerOfTwo(const std::string& text) {
  const int v = std::atoi(text.c_str());
  return v >= 1 && (v & (v - 1)) == 0 ? std::string() : "must be a power of 2";
}

/// Checks options filled from the command line before any work: an invalid
/// value is a usage error.
template <typename Options>
void CheckUsage(const Options& options) {
  try {
    options.Check();
  } catch (const InvalidArgument& e) {
    throw UsageError(e.what());
  }
}

/// What every command that reads a sequence accepts: the sequence, --stride,
/// --max-frames,
/// --intrinsics.
struct SequenceArgs {
  std::string path;
  int stride = 1;
  size_t max_frames = 0;
  std::string intrinsics;
  std::string pose_correction;
  io::BagOptions bag;
  io::SequenceReaderOptions ReaderOptions() const;
};
void AddSequenceArgs(CLI::App* cmd, SequenceArgs* args);

/// --poses and --odometry (run, mesh, tsdf): where the camera poses come
/// from (pipeline::RunOptions::poses) and how they are estimated.
void AddPoseArgs(CLI::App* cmd, pipeline::RunOptions::Poses* poses,
                 odometry::PoseTrackerOptions* odometry);
/// The above and --dynamic-classes (run, mesh), bound to `run`.
void AddPoseArgs(CLI::App* cmd, pipeline::RunOptions* run);

/// --no-surface-patches (mesh, run): SceneBuilderOptions::cover_owned_voxels
/// off.
void AddSurfacePatchesFlag(CLI::App* cmd, bool* no_surface_patches);

/// --resolver-skip PASS[,PASS] and --list-resolver-passes (mesh, run): the
/// object decision's passes left out, for ablations (scripts/ablate_resolver).
void AddResolverSkipArgs(CLI::App* cmd, std::set<std::string>* skip_passes);

/// The effective options of `cmd` as YAML, every option with its value or
/// default (run.yaml; usable as `run --config`); `scene_only` leaves out
/// those that only change the outputs (the key a resumed run must match).
std::string EffectiveConfig(const CLI::App* cmd, bool scene_only);

/// What every command that runs ONNX models accepts: --registry, --threads,
/// --provider.
struct ModelArgs {
  std::string registry;
  int threads = 0;
  std::string provider = "auto";
  /// The installed registry merged with --registry.
  infer::ModelRegistry LoadRegistry() const;
  infer::OnnxModelOptions Runtime() const;
};
void AddModelArgs(CLI::App* cmd, ModelArgs* args);

/// --mask-margin and --decoder-kernel (segment, run):
/// PromptableOptions::mask_margin_logits and decoder_kernel, set after the
/// mask model's options come from the registry.
void AddMaskMarginArg(CLI::App* cmd, float* margin_logits,
                      std::string* decoder_kernel);

/// --object-detector (default yolox_nano) and its tuning options (segment,
/// run).
void AddObjectDetectorArgs(CLI::App* cmd,
                           segment::ObjectDetectorOptions* options);
/// After parsing: "none" turns the detector off; so does `--masks none`
/// (its boxes are mask prompts) unless --object-detector was given, which is
/// then a usage error. Sets the detector's runtime.
void FinishObjectDetectorArgs(const CLI::App& cmd, bool masks,
                              const infer::OnnxModelOptions& runtime,
                              segment::ObjectDetectorOptions* options);

void RegisterInfo(CLI::App& app);
void RegisterTsdf(CLI::App& app);
void RegisterSynth(CLI::App& app);
void RegisterFuse(CLI::App& app);
void RegisterEval(CLI::App& app);
/// `eval scene`, added to the eval command.
void AddEvalScene(CLI::App* eval);
void AddEvalTraj(CLI::App* eval);
void RegisterTrack(CLI::App& app);
void RegisterMesh(CLI::App& app);
void RegisterQuery(CLI::App& app);
void RegisterSegment(CLI::App& app);
void RegisterRun(CLI::App& app);
void RegisterView(CLI::App& app);

}  // namespace semrec::cli
