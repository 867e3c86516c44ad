// `semrec mesh <sequence> --labels ... --out DIR`: fusion + per-object meshing
// + USD.
#include <cstdio>

#include <fmt/format.h>

#include "commands.h"
#include "semrec/pipeline/reconstruct.h"

namespace semrec::cli {
namespace {

struct MeshArgs {
  SequenceArgs sequence;
  std::string labels = "gt";
  std::string out;
  pipeline::ReconstructOptions options;
  bool no_ply = false;
  std::string gravity = "auto";
  bool no_structure = false;
  std::string merge = "voxel";
  bool two_pass = false;
  bool no_surface_patches = false;
};

void RunMesh(MeshArgs args) {
  args.options.write_ply = !args.no_ply;
  args.options.scene.gravity = fuse::ParseGravity(args.gravity);
  args.options.scene.stream_volumes = !args.two_pass;
  args.options.scene.cover_owned_voxels = !args.no_surface_patches;
  args.options.scene.fusion.stuff_per_class = !args.no_structure;
  args.options.scene.fusion.merge = fuse::ParseMerge(args.merge);
  CheckUsage(args.options);
  io::SequenceReaderOptions reader_options = args.sequence.ReaderOptions();
  reader_options.max_depth_m = args.options.scene.meshing.tsdf.max_depth_m;
  const io::SequenceReader reader =
      io::SequenceReader::Open(args.sequence.path, reader_options);
  const auto source = fuse::SegmentationSource::Create(args.labels, reader);
  const pipeline::ReconstructResult r =
      pipeline::Reconstruct(reader, *source, args.options, args.out);
  std::printf(
      "%s",
      fmt::format(
          "{} frames -> {} objects + {} structure ({} triangles), {} "
          "people{}{}; gravity: {}; wrote {}/scene.usda in {:.1f} s\n",
          r.frames, r.scene.objects - r.scene.structure, r.scene.structure,
          r.scene.triangles, r.scene.people,
          r.scene.skipped_empty_objects > 0
              ? fmt::format(", {} empty skipped", r.scene.skipped_empty_objects)
              : "",
          r.scene.patches > 0
              ? fmt::format(", {} surface patches", r.scene.patches)
              : "",
          r.scene.gravity.method, args.out, r.seconds)
          .c_str());
}

}  // namespace

void RegisterMesh(CLI::App& app) {
  auto args = std::make_shared<MeshArgs>();
  CLI::App* cmd =
      app.add_subcommand("mesh",
                         "Reconstruct a labelled sequence into a USD scene: "
                         "semantics-guided fusion finds the "
                         "objects, each object's pixels go into its own TSDF "
                         "volume, meshes are written as USD "
                         "Mesh prims with class labels (scene.usda -> "
                         "static.usda) and as PLY per object; tracked people "
                         "(--people) become time-sampled prims in "
                         "dynamic.usda.");
  AddSequenceArgs(cmd, &args->sequence);
  cmd->add_option("--labels", args->labels,
                  "Segmentation: 'gt', a folder with instance/, semantic/ and "
                  "classes.json, or "
                  "'single:<class>'")
      ->capture_default_str();
  cmd->add_option("--out,-o", args->out, "Output folder")->required();
  cmd->add_option("--people", args->options.people,
                  "Tracked people for dynamic.usda (time-sampled prims): "
                  "'gt' (the sequence's person layer) or the persons/ folder "
                  "written by 'semrec track <sequence> --out DIR'");
  cmd->add_option("--voxel-size-m",
                  args->options.scene.meshing.tsdf.voxel_size_m,
                  "Voxel size of each object's TSDF (m)")
      ->capture_default_str();
  cmd->add_option("--sdf-trunc-m", args->options.scene.meshing.tsdf.sdf_trunc_m,
                  "SDF truncation distance (m)")
      ->capture_default_str();
  cmd->add_option("--max-depth-m", args->options.scene.meshing.tsdf.max_depth_m,
                  "Ignore depth beyond this (m)")
      ->capture_default_str();
  cmd->add_option("--min-observations",
                  args->options.scene.meshing.min_observations,
                  "Mesh only objects seen in at least this many frames")
      ->capture_default_str();
  cmd->add_option("--alpha", args->options.scene.fusion.alpha,
                  "Fusion: merge when sigma > alpha")
      ->capture_default_str();
  cmd->add_option("--merge", args->merge,
                  "Fusion: paper (sigma > alpha alone), evidence (also "
                  "merge parts that views show inside one mask, vote each "
                  "object's class, fold fragments; see summary.json events) "
                  "or voxel (evidence, then classes and objects decided per "
                  "5 cm map voxel by every view: structure only on its "
                  "planes, fragments judged by visibility)")
      ->check(CLI::IsMember({"paper", "evidence", "voxel"}))
      ->capture_default_str();
  cmd->add_option("--up-axis", args->options.scene.stage.up_axis,
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
                  "in summary.json and the USD layer's customLayerData")
      ->capture_default_str();
  cmd->add_flag("--no-structure", args->no_structure,
                "Fuse stuff classes (wall, floor, ceiling...) like objects "
                "instead of one /World/Structure prim per class");
  cmd->add_flag("--no-ply", args->no_ply, "Do not write PLY per object");
  AddSurfacePatchesFlag(cmd, &args->no_surface_patches);
  cmd->add_flag("--two-pass", args->two_pass,
                "Build the object volumes in a second pass over the frames "
                "with fusion's final ids (the reference for the default "
                "streaming volumes, which are combined when objects merge)");
  cmd->add_flag("--usdz", args->options.usdz,
                "Also write scene.usdz: objects and people in one layer, "
                "packaged per the USDZ spec (stored, 64-byte aligned)");
  cmd->add_flag("--glb", args->options.glb,
                "Also write scene.glb (glTF 2.0 binary, Y-up: Blender, "
                "three.js and most tools "
                "open it): one node per object, vertex colours, class and id "
                "in extras, people "
                "as animated nodes");
  cmd->add_flag("--overwrite", args->options.overwrite,
                "Write into a non-empty output folder");
  AddResolverSkipArgs(cmd, &args->options.scene.fusion.map_objects.skip_passes);
  cmd->callback([args] { RunMesh(*args); });
}

}  // namespace semrec::cli
