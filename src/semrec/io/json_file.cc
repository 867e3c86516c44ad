#include "semrec/io/json_file.h"

#include <string>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"

namespace semrec::io {

nlohmann::json ReadJsonFile(const std::filesystem::path& path) {
  try {
    return nlohmann::json::parse(ReadTextFile(path));
  } catch (const nlohmann::json::exception& e) {
    throw FormatError(path, std::string("invalid JSON: ") + e.what());
  }
}

}  // namespace semrec::io
