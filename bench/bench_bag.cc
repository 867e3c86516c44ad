// Reading frames from ROS 2 bags vs the same frames from a folder.
// The 100 7-Scenes chess frames (real colour and depth) are written as bags
// the way a robot records them (io/test_bags.h: TF chain, CameraInfo), in
// each storage and encoding; every variant is opened (indexed) and all its
// frames read and decoded, in one process. Then memory: a bag 10x longer
// (the frames repeated at 160x120) must not take more memory to read than
// the short one beyond its index.
//   build/bench/bench_bag [SEVEN_SCENES_FOLDER]
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include "bench_util.h"
#include "semrec/core/error.h"
#include "semrec/core/stopwatch.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/io/test_bags.h"
#include "semrec/testing/test_util.h"

namespace fs = std::filesystem;
using namespace semrec;

namespace {

// Resident memory now and at its peak (kB), from /proc/self/status.
std::pair<long, long> RssKb() {
  std::ifstream in("/proc/self/status");
  std::string key;
  long rss = 0, hwm = 0;
  while (in >> key) {
    if (key == "VmRSS:") in >> rss;
    if (key == "VmHWM:") in >> hwm;
  }
  return {rss, hwm};
}

// Opens and reads every frame; returns seconds.
double ReadAll(const fs::path& path, size_t* frames) {
  const Stopwatch t;
  const io::SequenceReader reader = io::SequenceReader::Open(path);
  double checksum = 0.0;
  for (size_t i = 0; i < reader.size(); ++i) {
    const Frame f = reader.Read(i);
    checksum += f.depth(f.depth.width() / 2, f.depth.height() / 2);
  }
  *frames = reader.size();
  if (checksum < 0) std::printf("%f\n", checksum);  // keep the reads
  return t.Elapsed();
}

std::vector<io::testing::BagFrame> Frames(const io::SequenceReader& r,
                                          int shrink, size_t repeat) {
  std::vector<io::testing::BagFrame> out;
  for (size_t k = 0; k < repeat; ++k) {
    for (size_t i = 0; i < r.size(); ++i) {
      const Frame f = r.Read(i);
      io::testing::BagFrame b;
      const int w = f.color.width() / shrink, h = f.color.height() / shrink;
      b.color = ColorImage(w, h, 3);
      b.depth_m = DepthImage(w, h);
      for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
          for (int c = 0; c < 3; ++c) {
            b.color(x, y, c) = f.color(x * shrink, y * shrink, c);
          }
          b.depth_m(x, y) = f.depth(x * shrink, y * shrink);
        }
      }
      b.T_world_camera = f.T_world_camera;
      b.timestamp_s = static_cast<double>(out.size()) / 30.0;
      out.push_back(std::move(b));
    }
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 3 && std::string(argv[1]) == "--memory") {
    const long before = RssKb().first;
    const io::SequenceReader reader = io::SequenceReader::Open(argv[2]);
    const long indexed = RssKb().first;
    for (size_t i = 0; i < reader.size(); ++i) reader.Read(i);
    const auto [rss, peak] = RssKb();
    std::printf(
        "  %5zu frames: %ld kB resident at start, %+ld kB indexed, "
        "peak %ld kB, %ld kB at the end\n",
        reader.size(), before, indexed - before, peak, rss);
    return 0;
  }
  try {
    const fs::path chess = argc > 1
                               ? fs::path(argv[1])
                               : bench::SampleDataDir() / "7scenes_chess_0_99";
    const io::SequenceReader folder = io::SequenceReader::Open(chess);
    semrec::testing::TempDir dir;
    const auto frames = Frames(folder, 1, 1);
    struct Variant {
      const char* name;
      io::testing::TestBagOptions o;
    };
    std::vector<Variant> variants(6);
    variants[0] = {"MCAP zstd, raw images", {}};
    variants[1] = {"MCAP lz4, raw images", {}};
    variants[1].o.compression = "lz4";
    variants[2] = {"MCAP uncompressed", {}};
    variants[2].o.compression = "";
    variants[3] = {"MCAP, jpeg + compressedDepth", {}};
    variants[3].o.compression = "";
    variants[3].o.compressed_color = true;
    variants[3].o.compressed_depth = true;
    variants[4] = {"SQLite, raw images", {}};
    variants[4].o.storage = "sqlite3";
    variants[5] = {"MCAP zstd, 32FC1 depth", {}};
    variants[5].o.float_depth = true;
    for (size_t v = 0; v < variants.size(); ++v) {
      io::testing::WriteTestBag(dir.path() / std::to_string(v), frames,
                                folder.intrinsics(), variants[v].o);
    }
    size_t n = 0;
    const double folder_s = ReadAll(chess, &n);
    std::printf("%-32s %8s %9s %8s\n", "source (100 chess frames)", "frames/s",
                "MB", "ratio");
    std::printf("%-32s %8.1f %9s %8.2f\n", "folder (jpg + png files)",
                n / folder_s, "", 1.0);
    for (size_t v = 0; v < variants.size(); ++v) {
      const double s = ReadAll(dir.path() / std::to_string(v), &n);
      double mb = 0;
      for (const auto& e :
           fs::recursive_directory_iterator(dir.path() / std::to_string(v))) {
        if (e.is_regular_file()) mb += e.file_size() / 1e6;
      }
      std::printf("%-32s %8.1f %9.1f %8.2f\n", variants[v].name, n / s, mb,
                  folder_s / s);
    }

    // Memory: reading a 10x longer bag (160x120 frames), each in a process
    // of its own (peak resident memory of the whole read).
    std::printf(
        "\npeak memory reading a bag (160x120 frames, MCAP zstd), "
        "own process:\n");
    for (const size_t repeat : {1, 10}) {
      const fs::path bag = dir.path() / ("long" + std::to_string(repeat));
      {
        const auto small = Frames(folder, 4, repeat);
        io::testing::WriteTestBag(bag, small, folder.intrinsics().Scaled(0.25),
                                  {});
      }
      const std::string cmd =
          std::string(argv[0]) + " --memory '" + bag.string() + "'";
      std::fflush(stdout);
      if (std::system(cmd.c_str()) != 0) throw Error("memory run failed");
    }
  } catch (const Error& e) {
    std::fprintf(stderr, "bench_bag: %s\n", e.what());
    return 1;
  }
  return 0;
}
