// semrec: RGB-D frames with poses -> semantically labelled, instance-tracked 3D
// scenes.
#include <cstdio>
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
