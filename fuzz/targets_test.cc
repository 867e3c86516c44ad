// Replays each fuzz target's seed corpus and every input a fuzzer once broke
// (fuzz/regressions/<target>/) through the normal test suite: a reader must
// accept or reject them with a semrec::Error, never crash or throw anything
// else (under the ASan/UBSan build of .ci/run, never touch bad memory).
#include <fstream>
#include <iterator>

#include <gtest/gtest.h>

#include "fuzz/targets.h"
#include "semrec/testing/test_util.h"

namespace fs = std::filesystem;

namespace semrec::fuzz {
namespace {

std::vector<fs::path> FilesIn(const fs::path& dir) {
  std::vector<fs::path> files;
  if (!fs::is_directory(dir)) return files;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.is_regular_file()) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::vector<uint8_t> Bytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

class FuzzRegression : public ::testing::TestWithParam<std::string> {};

TEST_P(FuzzRegression, SeedsAndPastFindingsAreHandled) {
  const Target& target = FindTarget(GetParam());
  const fs::path fuzz = semrec::testing::SourceDir() / "fuzz";
  const auto seeds = FilesIn(fuzz / "corpus" / target.name);
  ASSERT_FALSE(seeds.empty())
      << "no seed corpus in fuzz/corpus/" << target.name;
  int accepted = 0;
  for (const fs::path& file : seeds) {
    const auto bytes = Bytes(file);
    bool ok = false;
    EXPECT_NO_THROW(ok = RunOne(target, bytes.data(), bytes.size())) << file;
    accepted += ok ? 1 : 0;
  }
  // The seeds include valid files: the target reaches its parser's happy path.
  EXPECT_GT(accepted, 0) << "no seed of " << target.name << " is accepted";
  for (const fs::path& file : FilesIn(fuzz / "regressions" / target.name)) {
    const auto bytes = Bytes(file);
    EXPECT_NO_THROW(RunOne(target, bytes.data(), bytes.size())) << file;
  }
  // An empty file is rejected cleanly (or valid, where the format says so).
  EXPECT_EQ(RunOne(target, nullptr, 0), target.empty_is_valid);
}

std::vector<std::string> Names() {
  std::vector<std::string> names;
  for (const Target& t : Targets()) names.push_back(t.name);
  return names;
}

INSTANTIATE_TEST_SUITE_P(Targets, FuzzRegression, ::testing::ValuesIn(Names()),
                         [](const auto& info) { return info.param; });

}  // namespace
}  // namespace semrec::fuzz
