#include "semrec/core/logging.h"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "semrec/core/error.h"

namespace semrec {

void InitLogging(const std::string& level) {
  const spdlog::level::level_enum parsed = spdlog::level::from_str(level);
  // from_str maps unknown names to "off"; only accept that for the literal
  // "off".
  if (parsed == spdlog::level::off && level != "off") {
    throw InvalidArgument("unknown log level '" + level +
                          "' (use trace, debug, info, warn, error or off)");
  }
  static auto logger = spdlog::stderr_color_mt("semrec");
  spdlog::set_default_logger(logger);
  spdlog::set_pattern("[%H:%M:%S.%e] [%^%l%$] %v");
  spdlog::set_level(parsed);
}

}  // namespace semrec
