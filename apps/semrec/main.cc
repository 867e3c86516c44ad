// semrec: RGB-D frames with poses -> semantically labelled, instance-tracked 3D
// scenes.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <exception>

#include <CLI/CLI.hpp>

#include "commands.h"
#include "semrec/core/error.h"
#include "semrec/core/logging.h"

namespace {

int Run(int argc, char** argv) {
  CLI::App app{
      "semrec - semantic 3D reconstruction from RGB-D sequences.\n"
      "Sequences: a folder in one of the layouts semrec detects "
      "(Redwood/Open3D, 7-Scenes/3DMatch, "
      "TUM RGB-D, ScanNet .sens, a ROS 2 bag, or semrec's own "
      "sequence.yaml); see docs/usage.md.",
      "semrec"};
  app.set_version_flag("--version", "semrec " SEMREC_VERSION);
  std::string log_level = "info";
  app.add_option("--log-level", log_level,
                 "trace, debug, info, warn, error or off")
      ->capture_default_str();
  app.require_subcommand(1);
  semrec::cli::RegisterInfo(app);
  semrec::cli::RegisterTsdf(app);
  semrec::cli::RegisterSynth(app);
  semrec::cli::RegisterFuse(app);
  semrec::cli::RegisterEval(app);
  semrec::cli::RegisterTrack(app);
  semrec::cli::RegisterMesh(app);
  semrec::cli::RegisterQuery(app);
  semrec::cli::RegisterSegment(app);
  semrec::cli::RegisterRun(app);
  semrec::cli::RegisterView(app);
  app.parse_complete_callback([&] { semrec::InitLogging(log_level); });
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help / --version exit 0; usage errors exit 2 as documented (CLI11's
    // own codes are 105-114).
    return app.exit(e) == 0 ? 0 : 2;
  } catch (const semrec::cli::UsageError& e) {
    std::fprintf(stderr, "error: %s (see --help)\n", e.what());
    return 2;
  } catch (const semrec::Error& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "internal error: %s\n", e.what());
    return 3;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // Open3D's OpenMP threads spin after each parallel region, on the cores the
  // models and the integration thread need: 7-Scenes chess with estimated
  // poses took 194 s (602 ms per frame tracking the camera) and 134 s (191
  // ms) with passive waiting, 2 cores. libgomp reads the policy when it is
  // loaded, before main: start again with it set.
  if (std::getenv("OMP_WAIT_POLICY") == nullptr) {
    setenv("OMP_WAIT_POLICY", "PASSIVE", 1);
    execv("/proc/self/exe", argv);  // returns only on failure: go on as is
  }
  // Anything that escapes Run (e.g. while building the command line) still
  // ends with a message, not std::terminate.
  try {
    return Run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "internal error: %s\n", e.what());
  } catch (...) {
    std::fprintf(stderr, "internal error\n");
  }
  return 3;
}
