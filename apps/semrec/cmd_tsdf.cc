// `semrec tsdf <sequence> --out mesh.ply`: whole-scene TSDF fusion into one
// mesh.
#include <cstdio>
#include <filesystem>
#include <optional>
#include <vector>

#include <fmt/format.h>

#include "commands.h"
#include "semrec/core/progress.h"
#include "semrec/core/stopwatch.h"
#include "semrec/io/pose_io.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/mesh/tsdf_integrator.h"
#include "semrec/odometry/pose_tracker.h"

namespace semrec::cli {
namespace {

struct TsdfArgs {
  SequenceArgs sequence;
  std::string out;
  mesh::TsdfOptions tsdf;
  pipeline::RunOptions::Poses poses = pipeline::RunOptions::Poses::kAuto;
  odometry::PoseTrackerOptions odometry;
};

void RunTsdf(const TsdfArgs& args) {
  CheckUsage(args.tsdf);  // before any expensive work
  const Stopwatch start;
  io::SequenceReaderOptions reader_options = args.sequence.ReaderOptions();
  reader_options.require_poses =
      args.poses == pipeline::RunOptions::Poses::kFile;
  const io::SequenceReader reader =
      io::SequenceReader::Open(args.sequence.path, reader_options);
  // Estimated poses (asked for, or none in the recording) go beside the mesh.
  std::optional<odometry::PoseTracker> tracker;
  std::vector<io::StampedPose> estimated;
  if (pipeline::EstimatesPoses(args.poses, reader.index().has_poses)) {
    tracker.emplace(args.odometry, reader.intrinsics());
  }
  mesh::TsdfIntegrator tsdf(args.tsdf);
  {
    Progress progress("integrating", reader.size());
    for (size_t i = 0; i < reader.size(); ++i) {
      Frame frame = reader.Read(i);
      if (tracker) {
        frame.T_world_camera = tracker->Track(frame).T_world_camera;
        estimated.push_back({frame.timestamp_s, frame.T_world_camera});
      }
      tsdf.Integrate(frame);
      progress.Tick();
    }
  }
  const std::filesystem::path poses_file =
      std::filesystem::path(args.out).replace_extension(".poses.txt");
  if (tracker) io::WriteTumTrajectory(poses_file, estimated);
  const auto mesh = tsdf.ExtractMesh();
  mesh::WriteMeshPly(args.out, *mesh);
  const double seconds = start.Elapsed();
  std::printf(
      "%s",
      fmt::format(
          "{}: {} frames ({} layout) -> {} vertices, {} triangles in {:.2f} s; "
          "wrote {}{}\n",
          reader.root().string(), reader.size(), reader.layout(),
          mesh->vertices_.size(), mesh->triangles_.size(), seconds, args.out,
          tracker ? fmt::format(" and the estimated poses {} ({} keyframes, "
                                "{} frames not tracked)",
                                poses_file.string(), tracker->keyframes(),
                                tracker->lost_frames())
                  : "")
          .c_str());
}

}  // namespace

void RegisterTsdf(CLI::App& app) {
  auto args = std::make_shared<TsdfArgs>();
  CLI::App* cmd =
      app.add_subcommand("tsdf",
                         "Integrate all frames of a sequence into one Open3D "
                         "ScalableTSDFVolume and write "
                         "the triangle mesh (binary PLY with vertex colours).");
  AddSequenceArgs(cmd, &args->sequence);
  cmd->add_option("--out,-o", args->out,
                  "Output mesh (.ply), written atomically")
      ->required();
  AddPoseArgs(cmd, &args->poses, &args->odometry);
  cmd->add_option("--voxel-size-m", args->tsdf.voxel_size_m,
                  "TSDF voxel edge length (m)")
      ->capture_default_str();
  cmd->add_option("--sdf-trunc-m", args->tsdf.sdf_trunc_m,
                  "SDF truncation distance (m)")
      ->capture_default_str();
  cmd->add_option("--max-depth-m", args->tsdf.max_depth_m,
                  "Ignore depth beyond this (m)")
      ->capture_default_str();
  cmd->callback([args] { RunTsdf(*args); });
}

}  // namespace semrec::cli
