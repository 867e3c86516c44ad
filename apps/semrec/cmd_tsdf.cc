// `semrec tsdf <sequence> --out mesh.ply`: whole-scene TSDF fusion into one
// mesh.
#include <cstdio>

#include <fmt/format.h>

#include "commands.h"
#include "semrec/core/progress.h"
#include "semrec/core/stopwatch.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/mesh/tsdf_integrator.h"

namespace semrec::cli {
namespace {

struct TsdfArgs {
  SequenceArgs sequence;
  std::string out;
  mesh::TsdfOptions tsdf;
};

void RunTsdf(const TsdfArgs& args) {
  CheckUsage(args.tsdf);  // before any expensive work
  const Stopwatch start;
  const io::SequenceReader reader = io::SequenceReader::Open(
      args.sequence.path, args.sequence.ReaderOptions());
  mesh::TsdfIntegrator tsdf(args.tsdf);
  {
    Progress progress("integrating", reader.size());
    for (size_t i = 0; i < reader.size(); ++i) {
      tsdf.Integrate(reader.Read(i));
      progress.Tick();
    }
  }
  const auto mesh = tsdf.ExtractMesh();
  mesh::WriteMeshPly(args.out, *mesh);
  const double seconds = start.Elapsed();
  std::printf(
      "%s",
      fmt::format(
          "{}: {} frames ({} layout) -> {} vertices, {} triangles in {:.2f} s; "
          "wrote {}\n",
          reader.root().string(), reader.size(), reader.layout(),
          mesh->vertices_.size(), mesh->triangles_.size(), seconds, args.out)
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
