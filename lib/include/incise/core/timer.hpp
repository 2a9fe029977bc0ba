#pragma once
/// \file timer.hpp
/// Monotonic wall-clock stopwatch and the calling thread's CPU clock, used by solver reports,
/// the CLI and the benchmarks. No duration is asserted; `incise certify` asserts only a ratio of
/// two thread-CPU-time rates measured in the same rounds (docs/certify.md).

#include <chrono>
#include <ctime>

namespace incise {

/// Stopwatch started at construction; seconds() is the elapsed wall time in seconds.
class Timer {
 public:
  Timer() : start_(Clock::now()) {}
  void restart() { start_ = Clock::now(); }
  double seconds() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }

 private:
  using Clock = std::chrono::steady_clock;
  Clock::time_point start_;
};

/// CPU time consumed by the calling thread, in seconds (CLOCK_THREAD_CPUTIME_ID): unlike wall
/// time it does not grow when other jobs share the machine.
inline double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

/// CPU time consumed by the whole process — every thread, BLAS workers included — in seconds
/// (CLOCK_PROCESS_CPUTIME_ID): what a solve costs the machine (issue 19).
inline double process_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

}  // namespace incise
