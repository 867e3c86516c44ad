#include "commands.h"

namespace semrec::cli {

io::SequenceReaderOptions SequenceArgs::ReaderOptions() const {
  io::SequenceReaderOptions options;
  options.stride = stride;
  options.max_frames = max_frames;
  options.intrinsics_path = intrinsics;
  options.pose_correction_path = pose_correction;
  return options;
}

void AddSequenceArgs(CLI::App* cmd, SequenceArgs* args) {
  cmd->add_option("sequence", args->path, "Sequence folder (or sequence.yaml)")
      ->required();
  cmd->add_option("--stride", args->stride, "Use every n-th frame")
      ->capture_default_str();
  cmd->add_option("--max-frames", args->max_frames,
                  "Use at most this many frames (0 = all)")
      ->capture_default_str();
  cmd->add_option("--intrinsics", args->intrinsics,
                  "Override intrinsics: Open3D JSON or 3x3 K matrix text file");
  cmd->add_option("--pose-correction", args->pose_correction,
                  "YAML with pre/post 4x4 matrices: T_world_camera = pre * "
                  "pose * post (e.g. data/poses/bonn_rgbd_dynamic.yaml for "
                  "the Bonn RGB-D Dynamic dataset's mocap poses)");
}

infer::ModelRegistry ModelArgs::LoadRegistry() const {
  infer::ModelRegistry r = infer::ModelRegistry::LoadDefault();
  if (!registry.empty()) r.Merge(infer::ModelRegistry::Load(registry));
  return r;
}

infer::OnnxModelOptions ModelArgs::Runtime() const {
  infer::OnnxModelOptions runtime;
  runtime.intra_op_threads = threads;
  runtime.provider = provider;
  return runtime;
}

void AddModelArgs(CLI::App* cmd, ModelArgs* args) {
  cmd->add_option("--registry", args->registry,
                  "Extra model registry file (your own exports; see "
                  "docs/models.md)");
  cmd->add_option("--threads", args->threads,
                  "Inference threads (0 = all cores)")
      ->capture_default_str();
  cmd->add_option("--provider", args->provider, "auto, cpu or cuda")
      ->capture_default_str();
}

}  // namespace semrec::cli
