#include "commands.h"

#include <algorithm>
#include <cstdio>
#include <sstream>

#include <fmt/format.h>

#include "semrec/fuse/map_objects.h"

namespace semrec::cli {

io::SequenceReaderOptions SequenceArgs::ReaderOptions() const {
  io::SequenceReaderOptions options;
  options.stride = stride;
  options.max_frames = max_frames;
  options.intrinsics_path = intrinsics;
  options.pose_correction_path = pose_correction;
  options.bag = bag;
  return options;
}

void AddPoseArgs(CLI::App* cmd, pipeline::RunOptions::Poses* poses,
                 odometry::PoseTrackerOptions* odometry) {
  cmd->add_option_function<std::string>(
         "--poses",
         [poses](const std::string& text) {
           *poses = pipeline::ParsePoses(text);
         },
         "file: the recording's poses (refused without); estimate: from the "
         "frames, in the same pass (RGB-D odometry, tracked people left "
         "out); auto: the recording's when it has them, else estimated")
      ->default_str(pipeline::PosesName(*poses))
      ->check(CLI::IsMember({"file", "estimate", "auto"}));
  cmd->add_option_function<std::string>(
         "--odometry",
         [odometry](const std::string& text) {
           odometry->method = odometry::ParseMethod(text);
         },
         "Estimated poses: frame-to-keyframe (odometry to the last keyframe, "
         "the previous frame when that fails), frame-to-frame, or "
         "frame-to-model (then ICP against the latest keyframes' clouds)")
      ->default_str(odometry::MethodName(odometry->method))
      ->check(CLI::IsMember(
          {"frame-to-keyframe", "frame-to-frame", "frame-to-model"}));
}

void AddPoseArgs(CLI::App* cmd, pipeline::RunOptions* run) {
  AddPoseArgs(cmd, &run->poses, &run->odometry);
  cmd->add_option("--dynamic-classes", run->dynamic_classes,
                  "Estimated poses: classes whose pixels are left out of "
                  "tracking where a frame is segmented (e.g. "
                  "'car,animal'; the tracked people always are)")
      ->delimiter(',');
}

void AddSurfacePatchesFlag(CLI::App* cmd, bool* no_surface_patches) {
  cmd->add_flag("--no-surface-patches", *no_surface_patches,
                "Do not cover the map voxels of things that no volume meshed "
                "(something thin, or seen once: a 2 cm TSDF gives it no "
                "surface) with small patches at their points; such objects "
                "then show holes, or no surface at all");
}

void AddResolverSkipArgs(CLI::App* cmd, std::set<std::string>* skip_passes) {
  std::string names;
  for (const std::string& n : fuse::MapResolverPassNames()) {
    names += (names.empty() ? "" : ", ") + n;
  }
  // An empty value (run.yaml writes one when no pass is left out) adds none.
  cmd->add_option_function<std::vector<std::string>>(
         "--resolver-skip",
         [skip_passes](const std::vector<std::string>& passes) {
           for (const std::string& p : passes) {
             if (!p.empty()) skip_passes->insert(p);
           }
         },
         "Leave out these passes of the object decision (--merge voxel; for "
         "ablations, docs/fusion.md): " +
             names)
      ->delimiter(',');  // names are checked with the options
  cmd->add_flag_callback(
      "--list-resolver-passes",
      [] {
        for (const std::string& n : fuse::MapResolverPassNames()) {
          std::printf("%s\n", n.c_str());
        }
        throw CLI::Success();
      },
      "Print the object decision's passes, in the order they run, and exit");
}

void AddSequenceArgs(CLI::App* cmd, SequenceArgs* args) {
  cmd->add_option("sequence", args->path,
                  "Sequence folder, sequence.yaml, a ROS 2 bag (*.mcap, "
                  "*.db3, or a folder with metadata.yaml) or a ScanNet .sens "
                  "file")
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
  const char* bags = "ROS 2 bags";
  cmd->add_option("--color-topic", args->bag.color_topic,
                  "Colour images (Image or CompressedImage; default: the "
                  "image topic named color/rgb, raw before compressed)")
      ->group(bags);
  cmd->add_option("--depth-topic", args->bag.depth_topic,
                  "Depth images (16UC1 mm, 32FC1 m, or compressedDepth; "
                  "default: the image topic named depth, aligned/registered "
                  "first)")
      ->group(bags);
  cmd->add_option("--camera-info-topic", args->bag.camera_info_topic,
                  "CameraInfo of the colour camera (default: the one beside "
                  "the colour topic)")
      ->group(bags);
  cmd->add_option("--pose-source", args->bag.pose_source,
                  "tf, or an Odometry / PoseStamped topic")
      ->capture_default_str()
      ->group(bags);
  cmd->add_option("--world-frame", args->bag.world_frame,
                  "TF frame the poses are in (default: map, then odom, then "
                  "the TF root above the camera)")
      ->group(bags);
  cmd->add_option("--camera-frame", args->bag.camera_frame,
                  "TF frame of the colour camera (default: the colour "
                  "images' header.frame_id)")
      ->group(bags);
  cmd->add_option("--sync-tol-ms", args->bag.sync_tol_ms,
                  "Colour and depth pair up when their stamps differ by at "
                  "most this")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber)
      ->group(bags);
}

namespace {

// Options that change where or how often things are written, not the scene:
// a run may be resumed with other values.
bool AffectsOnlyOutputs(const std::string& key) {
  for (const char* k : {"out", "snapshot-every", "checkpoint-every", "strict",
                        "threads", "provider", "no-overlays", "no-ply", "usdz",
                        "glb", "no-report", "no-report-pictures"}) {
    if (key == k) return true;
  }
  return false;
}

}  // namespace

std::string EffectiveConfig(const CLI::App* cmd, bool scene_only) {
  std::istringstream toml(cmd->config_to_str(/*default_also=*/true));
  std::string out =
      fmt::format("# semrec {}: the effective options\n", cmd->get_name());
  for (std::string line; std::getline(toml, line);) {
    const size_t eq = line.find('=');
    if (line.empty() || line[0] == '#' || line[0] == '[' ||
        eq == std::string::npos) {
      continue;
    }
    std::string key = line.substr(0, eq), value = line.substr(eq + 1);
    if (key == "config" || key == "resume" || key == "overwrite" ||
        key == "list-resolver-passes") {
      continue;
    }
    if (scene_only && AffectsOnlyOutputs(key)) continue;
    if (value == "\"\"" || value.empty()) value = "\"\"";
    out += fmt::format("{}: {}\n", key, value);
  }
  return out;
}

infer::ModelRegistry ModelArgs::LoadRegistry() const {
  return infer::ModelRegistry::LoadDefaultWith(registry);
}

infer::OnnxModelOptions ModelArgs::Runtime() const {
  infer::OnnxModelOptions runtime;
  runtime.intra_op_threads = threads;
  runtime.provider = infer::ParseProvider(provider);
  return runtime;
}

void AddModelArgs(CLI::App* cmd, ModelArgs* args) {
  cmd->add_option("--registry", args->registry,
                  "Extra model registry file (your own exports; see "
                  "docs/models.md)");
  cmd->add_option("--threads", args->threads,
                  "Inference threads (0 = all cores)")
      ->capture_default_str();
  cmd->add_option("--provider", args->provider,
                  "Where the models run: auto (CUDA when ONNX Runtime can "
                  "use it, else the CPU), cpu or cuda (fail without CUDA)")
      ->check(CLI::IsMember({"auto", "cpu", "cuda"}))
      ->capture_default_str();
}

void AddMaskMarginArg(CLI::App* cmd, float* margin_logits,
                      std::string* decoder_kernel) {
  cmd->add_option(
         "--decoder-kernel", *decoder_kernel,
         "Mask generation: decode prompts with semrec's own decoder "
         "kernel: on (fp32, the same masks up to float rounding), "
         "bf16 (products on bf16 inputs, CPUs with AVX512_BF16; "
         "measured 1.35x faster per prompt than on, the same masks on the "
         "benchmark's frames), off (ONNX Runtime), auto (bf16 where "
         "the CPU has it, else on with AVX-512, else off; "
         "docs/models.md)")
      ->check(CLI::IsMember({"auto", "on", "bf16", "off"}))
      ->capture_default_str();
  cmd->add_option("--mask-margin", *margin_logits,
                  "Mask generation: upscale a mask only near its edge, where "
                  "its preview holds a logit under this magnitude (elsewhere "
                  "the preview decides; 0 = everywhere, exact: 1.16x slower "
                  "full frames; bench/bench_prompts)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
}

void AddObjectDetectorArgs(CLI::App* cmd,
                           segment::ObjectDetectorOptions* options) {
  options->model = "yolox_nano";
  cmd->add_option("--object-detector", options->model,
                  "Object detector (registry name, e.g. yolox_nano) as a "
                  "second source of class evidence: its detections of "
                  "classes the label set has (data/class_maps/) become box "
                  "prompts, and a mask that matches one adds the detected "
                  "class, weighted by its score, to its vote (and stuff such "
                  "as wall gives way by 1 - score); none = off (also with "
                  "--masks none)")
      ->capture_default_str();
  cmd->add_option("--object-score", options->score_threshold,
                  "Ignore object detections below this score")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option("--object-weight", options->weight,
                  "A matched detection adds weight x score to its class's "
                  "share of the mask's semantic pixels")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--object-part-share", options->part_containment,
                  "A smaller mask with this share of its pixels inside a "
                  "detection's mask takes its evidence as a part (0 = off)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option("--object-mask-iou", options->min_predicted_iou,
                  "A detection no mask matches adds its own mask when the "
                  "decoder's predicted IoU is >= this (above 1 = never)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  // An option, not a negating flag: run.yaml writes every option's value and
  // --config must read the same back.
  cmd->add_option("--object-stuff-yields", options->stuff_yields,
                  "In masks matching a detection, scale the pixel share of "
                  "stuff classes (wall, floor...) by 1 - score (false: only "
                  "the added weight)")
      ->capture_default_str();
  cmd->add_option("--object-join-parts", options->join_parts,
                  "Masks of one detected object that voted its class (its "
                  "seat, back, legs) become one instance (false: each mask "
                  "its own)")
      ->capture_default_str();
  cmd->add_option("--object-class-map", options->class_map,
                  "JSON map from detector class names to label-set class "
                  "names (default: data/class_maps/<detector "
                  "set>_to_<label set>.json)");
}

void FinishObjectDetectorArgs(const CLI::App& cmd, bool masks,
                              const infer::OnnxModelOptions& runtime,
                              segment::ObjectDetectorOptions* options) {
  if (options->model == "none") options->model.clear();
  if (!masks && options->enabled()) {
    CheckUsage(cmd.count("--object-detector") == 0,
               "--object-detector needs the mask model (its boxes are mask "
               "prompts): drop --masks none or give --object-detector none");
    options->model.clear();
  }
  options->runtime = runtime;
}

}  // namespace semrec::cli
