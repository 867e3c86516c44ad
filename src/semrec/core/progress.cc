#include "semrec/core/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "semrec/core/error.h"

namespace semrec {

void ProgressOptions::Check() const {
  CheckArgument(min_interval_s >= 0.0, "progress: min_interval_s must be >= 0");
  CheckArgument(line_interval_s >= 0.0,
                "progress: line_interval_s must be >= 0");
  CheckArgument(bar_width > 0 && bar_width <= 200,
                "progress: bar_width must be in (0, 200]");
}

std::string FormatDuration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  if (seconds < 60) return fmt::format("{:.1f}s", seconds);
  const int64_t s = std::lround(seconds);
  if (s < 3600) return fmt::format("{}m{:02}s", s / 60, s % 60);
  return fmt::format("{}h{:02}m", s / 3600, (s % 3600) / 60);
}

Progress::Progress(std::string label, size_t total,
                   const ProgressOptions& options, std::FILE* stream)
    : label_(std::move(label)),
      total_(total),
      options_(options),
      stream_(stream) {
  options_.Check();
  switch (options_.mode) {
    case ProgressOptions::Mode::kAuto:
      bar_ = stream_ != nullptr && isatty(fileno(stream_)) != 0;
      break;
    case ProgressOptions::Mode::kBar:
      bar_ = true;
      break;
    case ProgressOptions::Mode::kLines:
    case ProgressOptions::Mode::kOff:
      bar_ = false;
      break;
  }
  if (options_.mode == ProgressOptions::Mode::kOff) stream_ = nullptr;
}

Progress::~Progress() { Finish(); }

double Progress::ElapsedS() const { return since_start_.Elapsed(); }

std::string Progress::Render(bool bar) const {
  const double elapsed = ElapsedS();
  const double rate = elapsed > 0 ? done_ / elapsed : 0.0;
  std::string text = label_;
  if (total_ > 0) {
    const double fraction = std::min(1.0, static_cast<double>(done_) / total_);
    if (bar) {
      const int filled = static_cast<int>(fraction * options_.bar_width);
      text += fmt::format(" [{}{}]", std::string(filled, '#'),
                          std::string(options_.bar_width - filled, '-'));
    }
    text += fmt::format(" {}/{} {:3.0f}%", done_, total_, 100.0 * fraction);
  } else {
    text += fmt::format(" {}", done_);
  }
  text += rate >= 10 ? fmt::format(" {:.0f} it/s", rate)
                     : fmt::format(" {:.2f} it/s", rate);
  if (finished_ || (total_ > 0 && done_ >= total_)) {
    text += " in " + FormatDuration(elapsed);
  } else if (total_ > 0 && rate > 0) {
    text += " ETA " + FormatDuration((total_ - done_) / rate);
  }
  if (!detail_.empty()) text += " | " + detail_;
  return text;
}

void Progress::Emit(bool final) {
  if (stream_ == nullptr) return;
  const double now = ElapsedS();
  const double interval =
      bar_ ? options_.min_interval_s : options_.line_interval_s;
  if (!final && now - last_emit_s_ < interval) return;
  last_emit_s_ = now;
  emitted_done_ = done_;
  if (bar_) {
    // \r + erase-line redraws in place.
    std::fprintf(stream_, "\r\033[K%s%s", Render(true).c_str(),
                 final ? "\n" : "");
  } else {
    std::fprintf(stream_, "%s\n", Render(false).c_str());
  }
  std::fflush(stream_);
}

void Progress::Tick(size_t n) {
  if (finished_) return;
  done_ += n;
  Emit(false);
  if (options_.on_tick) options_.on_tick(done_, total_);
}

void Progress::Finish() {
  if (finished_) return;
  finished_ = true;
  // A line already reported completion: do not repeat it (a bar still needs its
  // newline).
  if (!bar_ && total_ > 0 && emitted_done_ == done_ && done_ >= total_) return;
  Emit(true);
}

}  // namespace semrec
