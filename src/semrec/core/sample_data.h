// Where the real sample recordings are: one lookup for the tests, the
// benchmarks and the demo's C++ side.
#pragma once

#include <filesystem>
#include <optional>

namespace semrec {

/// The sample recordings folder: $SEMREC_DATA when set, else ../shared/data
/// beside the source tree; nullopt when that folder does not exist.
std::optional<std::filesystem::path> SampleDataDir();

}  // namespace semrec
