// Helpers shared by the test suites.
#pragma once

#include <filesystem>
#include <optional>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace semrec::testing {

/// A fresh folder under the system temp dir, removed with its content on
/// destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const {
    return path_ / name;
  }

 private:
  std::filesystem::path path_;
};

/// The repository root (from SEMREC_SOURCE_DIR, set by CTest).
std::filesystem::path SourceDir();

/// The real sample data folder ($SEMREC_DATA, else ../shared/data beside the
/// repository), or nullopt when absent.
std::optional<std::filesystem::path> SampleDataDir();

/// The model cache ($SEMREC_MODELS, else .deps/models in the repository).
std::filesystem::path ModelDir();

void WriteText(const std::filesystem::path& path, const std::string& text);

/// A folder with the tiny test models of tests/models/make_tiny_models.py,
/// built once per process with Debian's python3-onnx (no downloads). Returns
/// an empty path (and prints the script's output) when they cannot be built.
std::filesystem::path TinyModelDir();
/// The tiny models' registry (TinyModelDir() / "registry.yaml").
std::filesystem::path TinyRegistryFile();

/// Parses a USD file with the independent parser (tinyusdz in node, installed
/// by scripts/setup) and returns its report {ok, error, meshes: [{path, points,
/// faceVertexCounts, faceVertexIndices}], layer}; nullopt when node or tinyusdz
/// is missing. `scratch` is a folder for the report file.
std::optional<nlohmann::json> ValidateUsd(const std::filesystem::path& file,
                                          const std::filesystem::path& scratch);

/// True when SEMREC_REQUIRE_ALL=1 (set by .ci/run): then a test that would
/// skip for missing sample data, models or tools fails instead, so CI cannot
/// stay green without testing what it claims.
bool RequireAll();

}  // namespace semrec::testing

/// Skips the current test with the reason `message` (a stream expression), or
/// fails it under SEMREC_REQUIRE_ALL=1. Returns from the test body either way.
#define SEMREC_SKIP(message)                                                \
  do {                                                                      \
    std::ostringstream semrec_skip_reason;                                  \
    semrec_skip_reason << message; /* NOLINT(bugprone-macro-parentheses) */ \
    if (::semrec::testing::RequireAll()) {                                  \
      GTEST_FAIL() << semrec_skip_reason.str()                              \
                   << " [a skip is a failure under SEMREC_REQUIRE_ALL=1]";  \
    }                                                                       \
    GTEST_SKIP() << semrec_skip_reason.str();                               \
  } while (false)

/// Skips the current test (with the reason) unless the sample data set `name`
/// is present; binds `var` to its folder.
#define SEMREC_REQUIRE_SAMPLE_DATA(var, name)                                \
  const auto var##_root = ::semrec::testing::SampleDataDir();                \
  if (!var##_root || !std::filesystem::is_directory(*var##_root / (name))) { \
    SEMREC_SKIP("sample data '" << (name)                                    \
                                << "' not found: set SEMREC_DATA to the "    \
                                << "shared data folder (CI uses "            \
                                << "../shared/data)");                       \
  }                                                                          \
  const std::filesystem::path var = *var##_root / (name)
