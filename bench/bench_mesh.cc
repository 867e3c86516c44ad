// Meshing benchmark: per-frame integration cost of all per-object TSDF volumes
// (each object's pixels into its own volume) against one whole-frame Open3D
// volume on the same frames, same voxel size, in one run (goal: <= 1.2x;
// the measured ratio is in docs/results.md).
//   bench_mesh [frames=30]   (synthetic six-objects + office; Redwood if found)
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "semrec/core/file_util.h"
#include "semrec/core/sample_data.h"
#include "semrec/core/stopwatch.h"
#include "semrec/fuse/segments.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/mesh/object_mesher.h"
#include "semrec/mesh/tsdf_integrator.h"
#include "semrec/synth/generator.h"

namespace fs = std::filesystem;
using namespace semrec;

namespace {

struct Input {
  std::string name;
  std::vector<Frame> frames;
  std::vector<LabelMap> labels;  // instance maps; 0 = no object
};

Input Synthetic(const std::string& preset, int frames, const fs::path& dir) {
  synth::SynthOptions o = synth::SynthOptions::Preset(preset);
  o.frames = frames;
  o.overwrite = true;
  ProgressOptions quiet;
  quiet.mode = ProgressOptions::Mode::kOff;
  synth::WriteSyntheticSequence(o, dir, quiet);
  const io::SequenceReader reader = io::SequenceReader::Open(dir);
  const auto source = fuse::SegmentationSource::Create("gt", reader);
  Input in{preset, {}, {}};
  for (size_t i = 0; i < reader.size(); ++i) {
    in.frames.push_back(reader.Read(i));
    in.labels.push_back(source->Get(reader, i).instance);
  }
  return in;
}

Input Redwood(const fs::path& dir) {
  const io::SequenceReader reader = io::SequenceReader::Open(dir);
  Input in{"redwood (1 label)", {}, {}};
  for (size_t i = 0; i < reader.size(); ++i) {
    in.frames.push_back(reader.Read(i));
    in.labels.emplace_back(in.frames.back().depth.width(),
                           in.frames.back().depth.height(), 1, uint16_t{1});
  }
  return in;
}

void Run(const Input& in) {
  const mesh::ObjectMeshingOptions options;
  // Whole frame, the reference.
  mesh::TsdfIntegrator whole(options.tsdf);
  Stopwatch start;
  for (const Frame& f : in.frames) whole.Integrate(f);
  const double whole_s = start.Elapsed();
  start.Lap();
  const size_t whole_vertices = whole.ExtractMesh()->vertices_.size();
  const double whole_mesh_s = start.Elapsed();
  // Per object.
  mesh::ObjectMesher mesher(options);
  double objects_s = 0;
  for (size_t i = 0; i < in.frames.size(); ++i) {
    std::set<uint16_t> ids;
    for (int v = 0; v < in.labels[i].height(); ++v)
      for (int u = 0; u < in.labels[i].width(); ++u)
        if (in.labels[i](u, v) != 0) ids.insert(in.labels[i](u, v));
    std::vector<std::pair<uint16_t, uint32_t>> mapping;
    for (uint16_t id : ids) mapping.emplace_back(id, id);
    start.Lap();
    mesher.Integrate(in.frames[i], in.labels[i], mapping);
    objects_s += start.Elapsed();
  }
  const size_t n = in.frames.size();
  std::printf("%-20s %6zu %8zu %12.1f %12.1f %8.2fx %10.1f %10zu\n",
              in.name.c_str(), n, mesher.num_objects(), 1e3 * whole_s / n,
              1e3 * objects_s / n, objects_s / whole_s, 1e3 * whole_mesh_s,
              whole_vertices);
}

}  // namespace

int main(int argc, char** argv) {
  const int frames = argc > 1 ? std::atoi(argv[1]) : 30;
  if (frames <= 0) {
    std::fprintf(stderr, "usage: bench_mesh [frames]\n");
    return 2;
  }
  const fs::path tmp = fs::temp_directory_path() / "semrec_bench_mesh";
  std::printf(
      "Integration per frame: one whole-frame volume vs per-object volumes "
      "(2 cm voxels)\n");
  std::printf("%-20s %6s %8s %12s %12s %9s %10s %10s\n", "input", "frames",
              "objects", "whole ms", "objects ms", "ratio", "mesh ms",
              "vertices");
  for (const char* preset : {"six-objects", "office"})
    Run(Synthetic(preset, frames, tmp / preset));
  const fs::path redwood = semrec::SampleDataDir().value_or("../shared/data") /
                           "redwood_livingroom1_5";
  if (fs::exists(redwood)) Run(Redwood(redwood));
  fs::remove_all(tmp);
  return 0;
}
