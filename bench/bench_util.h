// Helpers the end-to-end benchmarks share.
#pragma once

#include <chrono>
#include <cstdlib>
#include <filesystem>

#include "semrec/core/file_util.h"
#include "semrec/core/progress.h"

namespace semrec::bench {

using Clock = std::chrono::steady_clock;

/// Seconds since `t`.
inline double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

/// No progress output (the benchmarks print their own tables).
inline ProgressOptions Quiet() {
  ProgressOptions p;
  p.mode = ProgressOptions::Mode::kOff;
  return p;
}

/// The real sample data: $SEMREC_DATA, else ../shared/data beside the
/// repository.
inline std::filesystem::path SampleDataDir() {
  const char* data = std::getenv("SEMREC_DATA");
  return data != nullptr
             ? std::filesystem::path(data)
             : ProjectDataDir().parent_path().parent_path() / "shared" / "data";
}

}  // namespace semrec::bench
