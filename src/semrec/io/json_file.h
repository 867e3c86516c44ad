// JSON files read with one error convention.
#pragma once

#include <filesystem>

#include <nlohmann/json.hpp>

namespace semrec::io {

/// Parses `path` as JSON. Throws IoError when it cannot be read and
/// FormatError ("invalid JSON: ...") naming the file when it does not parse.
nlohmann::json ReadJsonFile(const std::filesystem::path& path);

}  // namespace semrec::io
