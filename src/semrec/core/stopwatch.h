// Wall-clock timing of pipeline stages (steady clock, seconds).
#pragma once

#include <chrono>

namespace semrec {

class Stopwatch {
 public:
  /// Seconds since construction or the previous Lap(); starts a new lap.
  double Lap() {
    const auto now = std::chrono::steady_clock::now();
    const double s = std::chrono::duration<double>(now - last_).count();
    last_ = now;
    return s;
  }
  /// Seconds since construction or the previous Lap(), without a new lap.
  double Elapsed() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() -
                                         last_)
        .count();
  }

 private:
  std::chrono::steady_clock::time_point last_ =
      std::chrono::steady_clock::now();
};

}  // namespace semrec
