#pragma once
/// \file blas_threads.hpp
/// BLAS threading controlled by incise, per call site (docs/solvers.md "BLAS threads").
/// CHOLMOD's supernodal factorization and solves run their dense kernels through BLAS. A
/// multithreaded OpenBLAS starts its worker threads when the library loads and lets them spin
/// (sched_yield) for ≈ 0.1 s after every call that used them, so a process that only
/// occasionally calls BLAS burns a second core. Here: BLAS runs on one thread unless a call
/// site asks for more (a factorization estimated at ≥ parallel_flops flops), and the idle
/// workers are stopped ("parked") when no incise BLAS call is running.
/// The control is looked up at run time (dlsym of OpenBLAS's openblas_set_num_threads and
/// blas_thread_shutdown_) so that it follows the BLAS actually loaded (Debian's
/// update-alternatives may swap it after the build); with another BLAS every function here is a
/// no-op (blas_thread_control_available() is false).

#include <string>

namespace incise::linalg {

/// Default of BlasThreadSettings::parallel_flops: a CHOLMOD factorization estimated below this
/// many flops runs BLAS on one thread (docs/solvers.md, "BLAS threads": measurement, reported).
inline constexpr double kDefaultBlasParallelFlops = 2e8;

/// The library's BLAS threading policy and its origin.
struct BlasThreadSettings {
  int max_threads = 1;  ///< threads of a large factorization ("all cores")
  double parallel_flops = kDefaultBlasParallelFlops;  ///< flops from which max_threads are used
  std::string origin;  ///< where the two values came from (defaults / environment variables)
};

/// The policy: the thread count for a BLAS-backed operation estimated at `flops` flops — 1
/// below `parallel_flops`, `max_threads` from there on. Throws ParameterError for
/// max_threads < 1, a negative or NaN parallel_flops, or a negative/NaN flops.
int blas_threads_for(double flops, int max_threads, double parallel_flops);

/// Parses the overrides: `threads_env` (value of INCISE_BLAS_THREADS, an integer ≥ 1, or null
/// when unset) caps max_threads (default `available`, the count the BLAS started with, which
/// honours OPENBLAS_NUM_THREADS); `flops_env` (value of INCISE_BLAS_PARALLEL_FLOPS, a number
/// ≥ 0, or null) replaces parallel_flops. Throws ParameterError naming the variable and the
/// value for anything else (e.g. "0", "2x", "-1").
BlasThreadSettings parse_blas_thread_settings(const char* threads_env, const char* flops_env,
                                              int available);

/// The process's settings: parse_blas_thread_settings() of the environment, read once (first
/// call) with `available` = the BLAS's thread count at that moment (1 without control).
const BlasThreadSettings& blas_thread_settings();

/// True when the loaded BLAS exposes openblas_set_num_threads/openblas_get_num_threads.
bool blas_thread_control_available();

/// The BLAS's current thread count (openblas_get_num_threads); 1 without control.
int blas_threads();

/// Sets one BLAS thread and stops OpenBLAS's idle worker threads (they are recreated by
/// OpenBLAS on the next multithreaded call), unless an incise BLAS call is running in another
/// thread (a ScopedBlasThreads is alive): then only the last one to end parks. Call it once at
/// program start (the `incise` CLI does) to stop the spinning the BLAS started at load; the
/// first ScopedBlasThreads of the process also does. Safe to call repeatedly.
void park_blas_threads();

/// RAII: BLAS runs on (at least) `threads` threads while the object lives. Process-wide, for
/// every thread: the count in force is the largest of the live scopes' (one when none asks for
/// more); when the last scope ends, BLAS is parked (park_blas_threads()). Every incise BLAS
/// call site holds one (CholmodFactor::factorize and solve), so parking never stops a worker
/// an incise call is using. A BLAS call made outside incise concurrently with the end of a
/// scope is not covered: the application then owns the BLAS threading (set
/// OPENBLAS_NUM_THREADS=1 or call the BLAS's own control).
class ScopedBlasThreads {
 public:
  /// threads ≥ 1 (ParameterError otherwise); values above blas_thread_settings().max_threads
  /// are capped to it.
  explicit ScopedBlasThreads(int threads);
  ~ScopedBlasThreads();
  ScopedBlasThreads(const ScopedBlasThreads&) = delete;
  ScopedBlasThreads& operator=(const ScopedBlasThreads&) = delete;
  /// The count this scope asked for, after the cap.
  int threads() const { return threads_; }

 private:
  int threads_;
};

}  // namespace incise::linalg
