// Logging goes through spdlog; this sets the project's format and level in one
// place.
#pragma once

#include <string>

namespace semrec {

/// Sets the global log level ("trace", "debug", "info", "warn", "error", "off")
/// and a compact pattern on stderr. Throws InvalidArgument for an unknown
/// level.
void InitLogging(const std::string& level = "info");

}  // namespace semrec
