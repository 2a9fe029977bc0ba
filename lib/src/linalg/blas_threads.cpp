#include <incise/core/error.hpp>
#include <incise/linalg/blas_threads.hpp>

#include <dlfcn.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <map>
#include <mutex>
#include <string>

namespace incise::linalg {

namespace {

/// OpenBLAS's controls, looked up in the loaded libraries (null when absent).
struct BlasControl {
  void (*set)(int) = nullptr;
  int (*get)() = nullptr;
  int (*shutdown)() = nullptr;  // stops the worker threads; OpenBLAS recreates them on demand
  BlasControl() {
    // NOLINTBEGIN(cppcoreguidelines-pro-type-reinterpret-cast)
    set = reinterpret_cast<void (*)(int)>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
    get = reinterpret_cast<int (*)()>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
    shutdown = reinterpret_cast<int (*)()>(dlsym(RTLD_DEFAULT, "blas_thread_shutdown_"));
    // NOLINTEND(cppcoreguidelines-pro-type-reinterpret-cast)
    if (set == nullptr || get == nullptr) set = nullptr, get = nullptr, shutdown = nullptr;
  }
};

const BlasControl& control() {
  static const BlasControl c;
  return c;
}

/// Live scopes' requests (count per thread number), the count set and whether the initial
/// park happened, under one mutex.
struct ScopeState {
  std::mutex mutex;
  std::map<int, int> live;  // requested threads → number of live scopes asking for it
  int in_force = 0;         // last count set (0: never set)
  bool parked_once = false;
};

ScopeState& state() {
  static ScopeState s;
  return s;
}

void set_threads(ScopeState& s, int threads) {
  if (control().set != nullptr && s.in_force != threads) control().set(threads);
  s.in_force = threads;
}

void park_locked(ScopeState& s) {
  set_threads(s, 1);
  if (control().shutdown != nullptr) control().shutdown();
  s.parked_once = true;
}

}  // namespace

int blas_threads_for(double flops, int max_threads, double parallel_flops) {
  INCISE_CHECK_PARAM(max_threads >= 1, "blas_threads_for: max_threads must be at least 1");
  INCISE_CHECK_PARAM(parallel_flops >= 0.0, "blas_threads_for: parallel_flops must be >= 0");
  INCISE_CHECK_PARAM(flops >= 0.0, "blas_threads_for: flops must be >= 0");
  return flops >= parallel_flops ? max_threads : 1;
}

BlasThreadSettings parse_blas_thread_settings(const char* threads_env, const char* flops_env,
                                              int available) {
  INCISE_CHECK_PARAM(available >= 1, "parse_blas_thread_settings: available must be >= 1");
  BlasThreadSettings s;
  s.max_threads = available;
  s.origin =
      "max_threads " + std::to_string(available) + " (BLAS at start), parallel_flops " + "default";
  if (threads_env != nullptr) {
    char* end = nullptr;
    errno = 0;
    const long v = std::strtol(threads_env, &end, 10);
    if (end == threads_env || *end != '\0' || errno != 0 || v < 1 || v > 4096)
      throw ParameterError(std::string("INCISE_BLAS_THREADS = \"") + threads_env +
                           "\": expected an integer from 1 to 4096");
    s.max_threads = std::min(available, static_cast<int>(v));
    s.origin = "max_threads min(" + std::to_string(available) +
               ", INCISE_BLAS_THREADS = " + threads_env + ")";
  }
  if (flops_env != nullptr) {
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(flops_env, &end);
    if (end == flops_env || *end != '\0' || errno != 0 || !(v >= 0.0) || !std::isfinite(v))
      throw ParameterError(std::string("INCISE_BLAS_PARALLEL_FLOPS = \"") + flops_env +
                           "\": expected a finite number >= 0");
    s.parallel_flops = v;
    s.origin += std::string(", parallel_flops INCISE_BLAS_PARALLEL_FLOPS = ") + flops_env;
  }
  return s;
}

const BlasThreadSettings& blas_thread_settings() {
  static const BlasThreadSettings s = parse_blas_thread_settings(
      std::getenv("INCISE_BLAS_THREADS"),         // NOLINT(concurrency-mt-unsafe)
      std::getenv("INCISE_BLAS_PARALLEL_FLOPS"),  // NOLINT
      control().get != nullptr ? std::max(1, control().get()) : 1);
  return s;
}

bool blas_thread_control_available() {
  return control().set != nullptr;
}

int blas_threads() {
  return control().get != nullptr ? control().get() : 1;
}

void park_blas_threads() {
  (void)blas_thread_settings();  // records the BLAS's own count before it is lowered
  ScopeState& s = state();
  const std::lock_guard<std::mutex> lock(s.mutex);
  if (s.live.empty()) park_locked(s);
}

ScopedBlasThreads::ScopedBlasThreads(int threads) : threads_(threads) {
  INCISE_CHECK_PARAM(threads >= 1, "ScopedBlasThreads: threads must be at least 1");
  const BlasThreadSettings& settings = blas_thread_settings();
  threads_ = std::min(threads, settings.max_threads);
  ScopeState& s = state();
  const std::lock_guard<std::mutex> lock(s.mutex);
  if (!s.parked_once && s.live.empty()) park_locked(s);  // stop the spinning since load
  ++s.live[threads_];
  set_threads(s, s.live.rbegin()->first);
}

ScopedBlasThreads::~ScopedBlasThreads() {
  ScopeState& s = state();
  const std::lock_guard<std::mutex> lock(s.mutex);
  auto it = s.live.find(threads_);
  if (--it->second == 0) s.live.erase(it);
  if (s.live.empty()) {
    // Park only when the workers may have been woken; a 1-thread scope never woke them.
    if (s.in_force > 1) park_locked(s);
  } else {
    set_threads(s, s.live.rbegin()->first);
  }
}

}  // namespace incise::linalg
