#include <incise/core/baseline.hpp>

#include <algorithm>
#include <vector>

namespace incise {

namespace {

/// Compiler barrier: `p` escapes and memory may have been read or written, so the adds before
/// it cannot be folded away or hoisted out of the repetition loop (what Google Benchmark's
/// DoNotOptimize + ClobberMemory do).
inline void clobber_memory(const double* p) {
  asm volatile("" : : "r"(p) : "memory");
}

}  // namespace

VectorAddSample vector_add_sample(double cpu_seconds) {
  constexpr int kN = 1024;  // thesis §4.5.2: "repeated adds of a 1024-double vector"
  std::vector<double> a(kN, 1.0), b(kN, 1e-9);
  long reps = 0;
  const double start = thread_cpu_seconds();
  double elapsed = 0.0;
  do {
    for (int r = 0; r < 1000; ++r) {
      for (int i = 0; i < kN; ++i) a[i] += b[i];
      clobber_memory(a.data());
    }
    reps += 1000;
    elapsed = thread_cpu_seconds() - start;
  } while (elapsed < cpu_seconds);
  return {static_cast<double>(reps) * kN, elapsed};
}

double vector_add_mflops() {
  static const double cached = [] {
    // Best of 25 trials of 20 ms (0.5 s): on the 2-vCPU KVM guest we measure on, this loop's
    // rate drops from ~7,000 to ~3,500–4,500 MFLOP/s for stretches of 50–300 ms (same binary,
    // same addresses; contention on the host we cannot see). A short window can fall entirely
    // inside such a stretch; the best over a longer one is the machine's sustained rate, and it
    // makes every "% of baseline" conservative.
    constexpr int kTrials = 25;
    double best = 0.0;
    for (int trial = 0; trial < kTrials; ++trial)
      best = std::max(best, vector_add_sample(0.02).mflops());
    return best;
  }();
  return cached;
}

}  // namespace incise
