// The fuzz targets: every parser of outside input, fed arbitrary bytes. A
// target may throw semrec::Error (a clear message for a bad file is the right
// answer); anything else (a crash, a sanitizer report, another exception, a
// huge allocation) is a bug. The libFuzzer binaries (SEMREC_FUZZ=ON) and the
// regression test of the normal suite share these functions.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace semrec::fuzz {

struct Target {
  /// Short name: fuzz_<name> binary, fuzz/corpus/<name>/ seeds,
  /// fuzz/regressions/<name>/ inputs that once broke it.
  std::string name;
  /// What the target parses, for --help and the note.
  std::string description;
  /// The file name the input is written to (the readers dispatch on it).
  std::string file_name;
  /// Parses the file at `path` with every reader of this format.
  void (*parse)(const std::filesystem::path& path);
  /// Whether an empty file is a valid input (a MOT file without boxes).
  bool empty_is_valid = false;
};

/// All targets.
const std::vector<Target>& Targets();

/// The target called `name`; throws std::invalid_argument when unknown.
const Target& FindTarget(const std::string& name);

/// Writes `data` to the target's file in a private scratch folder and parses
/// it. Returns true when the parser accepted the input and false when it
/// rejected it with a semrec::Error; other exceptions propagate.
bool RunOne(const Target& target, const uint8_t* data, size_t size);

}  // namespace semrec::fuzz
