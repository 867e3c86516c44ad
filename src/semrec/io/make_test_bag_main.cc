// semrec_make_test_bag: writes a ROS 2 bag from any sequence semrec reads, as
// a robot would record it (io/test_bags.h), for the CLI tests and the bag
// benchmark.
//   semrec_make_test_bag SEQUENCE OUT [--storage mcap|sqlite3]
//       [--compression zstd|lz4|none] [--compressed-color] [--compressed-depth]
//       [--float-depth] [--pose-correction YAML] [--max-frames N] [--bare] [--sens: a ScanNet .sens]
#include <cstdio>
#include <string>

#include "semrec/core/error.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/io/test_bags.h"

int main(int argc, char** argv) {
  using namespace semrec;
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s SEQUENCE OUT [options]\n", argv[0]);
    return 2;
  }
  io::testing::TestBagOptions o;
  io::SequenceReaderOptions ro;
  bool sens = false;
  for (int a = 3; a < argc; ++a) {
    const std::string arg = argv[a];
    const std::string next = a + 1 < argc ? argv[a + 1] : "";
    if (arg == "--storage") {
      o.storage = next, ++a;
    } else if (arg == "--compression") {
      o.compression = next == "none" ? "" : next, ++a;
    } else if (arg == "--compressed-color") {
      o.compressed_color = true;
    } else if (arg == "--compressed-depth") {
      o.compressed_depth = true;
    } else if (arg == "--pose-correction") {
      ro.pose_correction_path = next, ++a;
    } else if (arg == "--max-frames") {
      ro.max_frames = std::stoul(next), ++a;
    } else if (arg == "--float-depth") {
      o.float_depth = true;
    } else if (arg == "--sens") {
      sens = true;
    } else if (arg == "--bare") {
      o.metadata_yaml = false;
    } else {
      std::fprintf(stderr, "unknown option %s\n", arg.c_str());
      return 2;
    }
  }
  try {
    const io::SequenceReader reader = io::SequenceReader::Open(argv[1], ro);
    std::vector<io::testing::BagFrame> frames;
    for (size_t i = 0; i < reader.size(); ++i) {
      const Frame f = reader.Read(i);
      io::testing::BagFrame b;
      b.color = f.color;
      b.depth_m = f.depth;
      b.T_world_camera = f.T_world_camera;
      // Stamps 1/30 s apart whatever the source says (TUM's are epoch).
      b.timestamp_s = i / 30.0;
      frames.push_back(std::move(b));
    }
    if (sens) {
      io::testing::WriteTestSens(argv[2], frames, reader.intrinsics(), true, 1);
    } else {
      io::testing::WriteTestBag(argv[2], frames, reader.intrinsics(), o);
    }
  } catch (const Error& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
