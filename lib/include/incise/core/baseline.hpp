#pragma once
/// \file baseline.hpp
/// The thesis' machine baseline (Nienhuys 2003, §4.5.2, Table 4.5): the MFLOP/s rate of a
/// repeated double vector add a ← a + b on 1024-double vectors, against which the thesis states
/// its solvers' speed ("% peak"). One implementation, used by `incise certify` (Table 4.5
/// comparison: vector_add_sample interleaved with the solvers) and by the benchmark binaries'
/// context (benchmarks/support).
///
/// Timings are CPU time of the calling thread (CLOCK_THREAD_CPUTIME_ID), so that a loaded
/// machine does not inflate every "% of baseline" figure. No absolute rate is asserted anywhere;
/// `incise certify` asserts only the ratio of a solver's rate to this one, measured in the same
/// rounds (docs/certify.md).

#include <incise/core/timer.hpp>

namespace incise {

/// One timed stretch of the baseline kernel.
struct VectorAddSample {
  double flops = 0.0;    ///< element adds executed (one flop each)
  double seconds = 0.0;  ///< thread CPU seconds they took
  /// flops / seconds / 1e6.
  double mflops() const { return flops / seconds / 1e6; }
};

/// Repeats a ← a + b on 1024-double vectors, 1000 repetitions at a time, until at least
/// `cpu_seconds` (> 0) of the calling thread's CPU time have passed. Not cached.
VectorAddSample vector_add_sample(double cpu_seconds);

/// Measured vector-add baseline in MFLOP/s (one flop per element add): best of 25 trials of
/// vector_add_sample(0.02) (the thesis used the best sustained rate; why the best and
/// not the mean: baseline.cpp). Computed on the first call and cached for the life of the
/// process; thread-safe.
double vector_add_mflops();

}  // namespace incise
