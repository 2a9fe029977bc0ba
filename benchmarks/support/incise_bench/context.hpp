#pragma once
/// \file context.hpp
/// Benchmark context shared by every incise benchmark binary.
///
/// - add_context(): records the run environment of every incise report (core/environment.hpp:
///   CPU model, compiler, build type, the BLAS shared object actually mapped into the process,
///   Eigen version; date, host and cores are Google Benchmark's own entries) and the measured
///   vector-add baseline, as Google Benchmark context entries (they appear in the JSON output).
/// - vector_add_mflops(): the thesis' machine baseline (§4.5, Table 4.5), forwarded to
///   incise::vector_add_mflops() (incise/core/baseline.hpp, shared with `incise certify`):
///   a ← a + b on 1024-double vectors, in MFLOP/s (one flop per element add), timed in thread
///   CPU time like Google Benchmark's rates, best of 5 trials.
/// - fma_peak_mflops(): the nominal double-precision FMA peak of one core, not measured:
///   clock_GHz × flops/cycle, with flops/cycle from the ISA (AVX-512: 32, AVX2+FMA: 16, AVX: 8,
///   SSE2: 4) and the clock from /proc/cpuinfo "cpu MHz".

#include <string>

namespace incise::bench {

/// Measured vector-add baseline in MFLOP/s (cached after the first call in a process).
double vector_add_mflops();

/// Nominal FMA peak of one core in MFLOP/s (see file comment); 0 when unknown.
double fma_peak_mflops();

/// Adds the environment, baseline and peak entries to the Google Benchmark context.
void add_context();

}  // namespace incise::bench

/// main() for an incise benchmark binary: Google Benchmark's main plus add_context().
#define INCISE_BENCHMARK_MAIN()                                         \
  int main(int argc, char** argv) {                                     \
    ::benchmark::Initialize(&argc, argv);                               \
    if (::benchmark::ReportUnrecognizedArguments(argc, argv)) return 1; \
    ::incise::bench::add_context();                                     \
    ::benchmark::RunSpecifiedBenchmarks();                              \
    ::benchmark::Shutdown();                                            \
    return 0;                                                           \
  }
