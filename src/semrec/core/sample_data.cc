#include "semrec/core/sample_data.h"

#include <cstdlib>

namespace fs = std::filesystem;

namespace semrec {

std::optional<fs::path> SampleDataDir() {
  if (const char* env = std::getenv("SEMREC_DATA");
      env != nullptr && *env != '\0') {
    if (fs::is_directory(env)) return fs::path(env);
    return std::nullopt;
  }
  // SEMREC_DEFAULT_DATA_DIR is <source>/data.
  const fs::path beside =
      fs::path(SEMREC_DEFAULT_DATA_DIR).parent_path().parent_path() / "shared" /
      "data";
  std::error_code ec;
  if (fs::is_directory(beside, ec)) return fs::canonical(beside, ec);
  return std::nullopt;
}

}  // namespace semrec
