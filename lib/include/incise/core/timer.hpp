#pragma once
/// \file timer.hpp
/// Monotonic wall-clock stopwatch used by solver reports and the CLI. Never used in assertions.

#include <chrono>

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

}  // namespace incise
