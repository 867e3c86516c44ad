// Wall-clock timing of pipeline stages (steady clock, seconds).
#pragma once

#include <chrono>
#include <ctime>

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

/// CPU time the calling thread has used, in seconds (not its waits; not the
/// time of threads it hands work to, such as ONNX Runtime's pool).
inline double ThreadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// CPU time all threads of the process have used, in seconds.
inline double ProcessCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// Wall and calling-thread CPU time of consecutive laps: a stage that
/// waited (for the cores, for another thread) shows wall > CPU.
class StageWatch {
 public:
  struct Lap {
    double wall = 0.0, cpu = 0.0;
  };
  Lap Next() {
    const double cpu = ThreadCpuSeconds();
    const Lap lap{wall_.Lap(), cpu - cpu_};
    cpu_ = cpu;
    return lap;
  }

 private:
  Stopwatch wall_;
  double cpu_ = ThreadCpuSeconds();
};

}  // namespace semrec
