// `semrec mesh <sequence> --labels ... --out DIR`: a labelled recording into
// a USD scene (fusion, per-object meshing), as `semrec run` with given labels.
#include <cstdio>

#include "commands.h"
#include "semrec/pipeline/run_sequence.h"
#include "semrec/tasks/run_task.h"

namespace semrec::cli {
namespace {

struct MeshArgs {
  SequenceArgs sequence;
  std::string labels = "gt";
  std::string out;
  /// Outputs, people (`given_people`) and the scene's options
  /// (`pipeline.scene`) bind here directly.
  pipeline::RunOptions run;
  bool no_ply = false;
  std::string gravity = "auto";
  bool no_structure = false;
  std::string merge = "voxel";
  bool no_surface_patches = false;
};

// The run of `semrec run --labels <labels>`: one pass, the same outputs
// (report.json, not a format of its own), without overlays and report.html.
void RunMesh(MeshArgs args, const CLI::App* cmd) {
  tasks::RunTaskOptions task;
  task.sequence = args.sequence.path;
  task.reader = args.sequence.ReaderOptions();
  task.out = args.out;
  task.labels = fuse::LabelSpec::Parse(args.labels);
  task.report_html = false;
  pipeline::RunOptions& run = args.run;
  run.config_text = EffectiveConfig(cmd, /*scene_only=*/false);
  run.write_ply = !args.no_ply;
  pipeline::ScenePipelineOptions& p = run.pipeline;
  // People only when given: a sequence's person layer alone does not add them.
  p.track_people = !run.given_people.empty();
  p.overlays = false;
  p.scene.gravity = fuse::ParseGravity(args.gravity);
  p.scene.cover_owned_voxels = !args.no_surface_patches;
  p.scene.fusion.stuff_per_class = !args.no_structure;
  p.scene.fusion.merge = fuse::ParseMerge(args.merge);
  CheckUsage(task.labels.given(),
             "mesh takes labels as they are (gt, a folder, single:CLASS); "
             "semrec run --labels models runs the models");
  task.run = run;
  CheckUsage(task);
  const tasks::RunTaskResult result = tasks::RunTask(task);
  std::printf("%s", pipeline::RunSummaryTable(result.run, args.out).c_str());
}

}  // namespace

void RegisterMesh(CLI::App& app) {
  auto args = std::make_shared<MeshArgs>();
  CLI::App* cmd = app.add_subcommand(
      "mesh",
      "Reconstruct a labelled sequence into a USD scene: "
      "semantics-guided fusion finds the "
      "objects, each object's pixels go into its own TSDF "
      "volume, meshes are written as USD "
      "Mesh prims with class labels (scene.usda -> "
      "static.usda) and as PLY per object; tracked people "
      "(--people) become time-sampled prims in "
      "dynamic.usda. The same run as 'semrec run --labels ...' "
      "(report.json and all), without the overlays "
      "and report.html.");
  AddSequenceArgs(cmd, &args->sequence);
  cmd->add_option("--labels", args->labels,
                  "Segmentation: 'gt', a folder with instance/, semantic/ and "
                  "classes.json, or "
                  "'single:<class>'")
      ->capture_default_str();
  cmd->add_option("--out,-o", args->out, "Output folder")->required();
  AddPoseArgs(cmd, &args->run);
  cmd->add_option("--people", args->run.given_people,
                  "Tracked people for dynamic.usda (time-sampled prims): "
                  "'gt' (the sequence's person layer) or the persons/ folder "
                  "written by 'semrec track <sequence> --out DIR'");
  cmd->add_option("--voxel-size-m",
                  args->run.pipeline.scene.meshing.tsdf.voxel_size_m,
                  "Voxel size of each object's TSDF (m)")
      ->capture_default_str();
  cmd->add_option("--sdf-trunc-m",
                  args->run.pipeline.scene.meshing.tsdf.sdf_trunc_m,
                  "SDF truncation distance (m)")
      ->capture_default_str();
  cmd->add_option("--max-depth-m",
                  args->run.pipeline.scene.meshing.tsdf.max_depth_m,
                  "Ignore depth beyond this (m)")
      ->capture_default_str();
  cmd->add_option("--min-observations",
                  args->run.pipeline.scene.meshing.min_observations,
                  "Mesh only objects seen in at least this many frames")
      ->capture_default_str();
  cmd->add_option("--alpha", args->run.pipeline.scene.fusion.alpha,
                  "Fusion: merge when sigma > alpha")
      ->capture_default_str();
  cmd->add_option(
         "--merge", args->merge,
         "Fusion: paper (sigma > alpha alone), evidence (also "
         "merge parts that views show inside one mask, vote each "
         "object's class, fold fragments; see report.json fusion_events) "
         "or voxel (evidence, then classes and objects decided per "
         "5 cm map voxel by every view: structure only on its "
         "planes, fragments judged by visibility)")
      ->check(CLI::IsMember({"paper", "evidence", "voxel"}))
      ->capture_default_str();
  cmd->add_option("--up-axis", args->run.pipeline.scene.stage.up_axis,
                  "USD up axis: Z or Y (the upright scene is turned so that "
                  "this axis points up; with --gravity none it is only "
                  "declared)")
      ->capture_default_str();
  cmd->add_option("--gravity", args->gravity,
                  "Write the scene upright (Z up, floor at z = 0): 'auto' "
                  "estimates up from the cameras and the horizontal planes "
                  "(a world that is already upright is kept as is), 'none' "
                  "keeps the sequence's world frame, 'x,y,z' gives the "
                  "world's up direction (e.g. 0,-1,0). The transform used is "
                  "in report.json and the USD layer's customLayerData")
      ->capture_default_str();
  cmd->add_flag("--no-structure", args->no_structure,
                "Fuse stuff classes (wall, floor, ceiling...) like objects "
                "instead of one /World/Structure prim per class");
  cmd->add_flag("--no-ply", args->no_ply, "Do not write PLY per object");
  AddSurfacePatchesFlag(cmd, &args->no_surface_patches);
  cmd->add_flag("--usdz", args->run.usdz,
                "Also write scene.usdz: objects and people in one layer, "
                "packaged per the USDZ spec (stored, 64-byte aligned)");
  cmd->add_flag("--glb", args->run.glb,
                "Also write scene.glb (glTF 2.0 binary, Y-up: Blender, "
                "three.js and most tools "
                "open it): one node per object, vertex colours, class and id "
                "in extras, people "
                "as animated nodes");
  cmd->add_flag("--overwrite", args->run.overwrite,
                "Write into a non-empty output folder");
  AddResolverSkipArgs(cmd,
                      &args->run.pipeline.scene.fusion.map_objects.skip_passes);
  cmd->callback([args, cmd] { RunMesh(*args, cmd); });
}

}  // namespace semrec::cli
