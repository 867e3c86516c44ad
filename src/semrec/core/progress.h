// Progress reporting for long loops: a bar with rate and ETA on a terminal,
// plain periodic lines otherwise (CI logs, pipes), nothing when disabled.
#pragma once

#include <cstddef>
#include <cstdio>
#include <functional>
#include <string>
#include <utility>

#include "semrec/core/stopwatch.h"

namespace semrec {

struct ProgressOptions {
  enum class Mode { kAuto, kBar, kLines, kOff };
  /// kAuto: a bar when the stream is a terminal, lines otherwise.
  Mode mode = Mode::kAuto;
  /// Minimum time between two updates (bar redraws or lines).
  double min_interval_s = 0.1;
  /// In line mode, also the minimum interval between lines.
  double line_interval_s = 5.0;
  /// Bar width in characters.
  int bar_width = 30;
  /// Called on every Tick() with (done, total), on the ticking thread, in any
  /// mode (kOff too): for callers that show progress their own way (the
  /// Python module). May throw to stop the loop.
  std::function<void(size_t, size_t)> on_tick;
  void Check() const;
};

/// Usage: `Progress progress("integrate", n); for (...) { ...; progress.Tick();
/// }` The destructor prints the final line if Finish() was not called.
class Progress {
 public:
  /// `stream` defaults to stderr so that stdout stays clean for results.
  Progress(std::string label, size_t total, const ProgressOptions& options = {},
           std::FILE* stream = stderr);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  /// Advances by `n` items.
  void Tick(size_t n = 1);
  /// Text shown after the rate (e.g. a per-stage time breakdown); shown from
  /// the next update on.
  void set_detail(std::string detail) { detail_ = std::move(detail); }
  /// Prints the final state (items, elapsed time, rate). Idempotent.
  void Finish();

  size_t done() const { return done_; }
  size_t total() const { return total_; }
  /// The text of the current state, e.g. "integrate [#####-----] 5/10 50% 2.0
  /// it/s ETA 3s".
  std::string Render(bool bar) const;

 private:
  double ElapsedS() const;
  void Emit(bool final);

  std::string label_;
  std::string detail_;
  size_t total_;
  ProgressOptions options_;
  std::FILE* stream_;
  bool bar_ = false;
  size_t done_ = 0;
  bool finished_ = false;
  Stopwatch since_start_;
  double last_emit_s_ = -1e9;
  size_t emitted_done_ = static_cast<size_t>(-1);
};

/// "1h02m", "3m05s", "12.3s".
std::string FormatDuration(double seconds);

}  // namespace semrec
