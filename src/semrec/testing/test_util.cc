#include "semrec/testing/test_util.h"
#include "semrec/core/file_util.h"
#include "semrec/core/sample_data.h"

#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <mutex>
#include <random>

namespace fs = std::filesystem;

namespace semrec::testing {

TempDir::TempDir() {
  static std::atomic<int> counter{0};
  std::random_device rd;
  path_ = fs::temp_directory_path() /
          ("semrec_test_" + std::to_string(getpid()) + "_" +
           std::to_string(counter++) + "_" + std::to_string(rd()));
  fs::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

bool RequireAll() {
  const char* env = std::getenv("SEMREC_REQUIRE_ALL");
  return env != nullptr && std::string(env) == "1";
}

fs::path SourceDir() {
  const char* env = std::getenv("SEMREC_SOURCE_DIR");
  return env != nullptr ? fs::path(env) : fs::current_path();
}

std::optional<fs::path> SampleDataDir() { return semrec::SampleDataDir(); }

fs::path TinyRegistryFile() { return TinyModelDir() / "registry.yaml"; }

fs::path TinyModelDir() {
  static fs::path dir;
  static std::once_flag once;
  std::call_once(once, [] {
    const fs::path out = fs::temp_directory_path() /
                         ("semrec-tiny-models-" + std::to_string(::getpid()));
    const fs::path script =
        SourceDir() / "tests" / "models" / "make_tiny_models.py";
    const std::string cmd =
        "/usr/bin/python3 " + script.string() + " " + out.string() + " 2>&1";
    if (std::system(cmd.c_str()) == 0) {
      dir = out;
      // Removed when the test process ends.
      std::atexit([] {
        std::error_code ec;
        fs::remove_all(dir, ec);
      });
    } else {
      std::cerr << "building the tiny test models failed: " << cmd << "\n";
    }
  });
  return dir;
}

fs::path ModelDir() { return DefaultModelDir(); }

void WriteText(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  out << text;
}

std::optional<nlohmann::json> ValidateUsd(const fs::path& file,
                                          const fs::path& scratch) {
  const fs::path pkg = SourceDir() / ".deps/node/node_modules/tinyusdz";
  if (!fs::is_regular_file(pkg / "tinyusdz.wasm") ||
      std::system("node --version >/dev/null 2>&1") != 0) {
    return std::nullopt;
  }
  const fs::path script = SourceDir() / "src/semrec/usd/validate_usd.mjs";
  const fs::path out = scratch / "validation.json";
  const std::string cmd = "node '" + script.string() + "' '" + pkg.string() +
                          "' '" + file.string() + "' > '" + out.string() +
                          "' 2>/dev/null";
  if (std::system(cmd.c_str()) != 0) return std::nullopt;
  std::ifstream in(out);
  return nlohmann::json::parse(in);
}

}  // namespace semrec::testing
