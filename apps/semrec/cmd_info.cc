// `semrec info <sequence>`: what the reader sees in a sequence.
#include <algorithm>
#include <cstdio>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "semrec/core/progress.h"
#include "semrec/io/sequence_reader.h"

namespace semrec::cli {
namespace {

struct InfoArgs {
  SequenceArgs sequence;
  bool json = false;
  size_t scan_frames = 0;
};

void RunInfo(const InfoArgs& args) {
  // A recording without poses is described too (run estimates them).
  io::SequenceReaderOptions options = args.sequence.ReaderOptions();
  options.require_poses = false;
  const io::SequenceReader reader =
      io::SequenceReader::Open(args.sequence.path, options);
  const bool has_poses = reader.index().has_poses;
  const std::string poses =
      has_poses
          ? reader.index().pose_source
          : "none (semrec run, mesh and tsdf estimate them: --poses auto)";
  const CameraIntrinsics& k = reader.intrinsics();

  // Depth range over the frames (all, or an evenly spaced subset): reads every
  // scanned frame.
  const size_t scan = args.scan_frames == 0
                          ? reader.size()
                          : std::min(args.scan_frames, reader.size());
  double min_depth = 1e30, max_depth = 0.0, valid_sum = 0.0;
  {
    Progress progress("scanning depth", scan);
    for (size_t s = 0; s < scan; ++s) {
      const size_t i = scan == reader.size() ? s : s * reader.size() / scan;
      const Frame frame = reader.Read(i);
      size_t valid = 0;
      for (float d : frame.depth.values()) {
        if (d <= 0.0f) continue;
        ++valid;
        min_depth = std::min<double>(min_depth, d);
        max_depth = std::max<double>(max_depth, d);
      }
      valid_sum += static_cast<double>(valid) / frame.depth.NumPixels();
      progress.Tick();
    }
  }
  if (max_depth == 0.0) min_depth = 0.0;
  const auto& frames = reader.index().frames;
  const double duration =
      frames.back().timestamp_s - frames.front().timestamp_s;

  if (args.json) {
    nlohmann::json j = {
        {"path", reader.root().string()},
        {"layout", reader.layout()},
        {"frames", reader.size()},
        {"width", k.width},
        {"height", k.height},
        {"intrinsics",
         {{"fx", k.fx}, {"fy", k.fy}, {"cx", k.cx}, {"cy", k.cy}}},
        {"intrinsics_source", reader.index().intrinsics_source},
        {"depth_scale", reader.index().depth_scale},
        {"details", reader.index().details},
        {"pose_source", reader.index().pose_source},
        {"has_poses", has_poses},
        {"depth_min_m", min_depth},
        {"depth_max_m", max_depth},
        {"valid_depth_fraction", scan > 0 ? valid_sum / scan : 0.0},
        {"frames_scanned", scan},
        {"trajectory_length_m", reader.TrajectoryLengthM()},
        {"duration_s", duration}};
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  std::printf(
      "%s",
      fmt::format(
          "path:              {}\n"
          "layout:            {}\n"
          "frames:            {}\n"
          "resolution:        {}x{}\n"
          "intrinsics:        fx={:.3f} fy={:.3f} cx={:.3f} cy={:.3f} ({})\n"
          "depth scale:       {} units/m\n"
          "poses:             {}\n"
          "depth range:       {:.3f} - {:.3f} m ({:.0f}% valid, {} frames "
          "scanned)\n"
          "trajectory length: {:.3f} m over {:.2f} s\n",
          reader.root().string(), reader.layout(), reader.size(), k.width,
          k.height, k.fx, k.fy, k.cx, k.cy, reader.index().intrinsics_source,
          reader.index().depth_scale, poses, min_depth, max_depth,
          scan > 0 ? 100.0 * valid_sum / scan : 0.0, scan,
          reader.TrajectoryLengthM(), duration)
          .c_str());
  for (const std::string& line : reader.index().details) {
    std::printf("%s\n", line.c_str());
  }
}

}  // namespace

void RegisterInfo(CLI::App& app) {
  auto args = std::make_shared<InfoArgs>();
  CLI::App* cmd =
      app.add_subcommand("info",
                         "Print a sequence's detected layout, frame count, "
                         "resolution, intrinsics, depth "
                         "range and trajectory length.");
  AddSequenceArgs(cmd, &args->sequence);
  cmd->add_flag("--json", args->json, "Print JSON instead of text");
  cmd->add_option("--scan-frames", args->scan_frames,
                  "Frames read for the depth range, evenly spaced (0 = all)")
      ->capture_default_str();
  cmd->callback([args] { RunInfo(*args); });
}

}  // namespace semrec::cli
