#pragma once
/// \file environment.hpp
/// The machine and build a result was produced on, recorded in every report (the certification
/// report and summary.json, the `incise run` summary JSON, the benchmark context), so two
/// numbers from different machines or builds are never compared unknowingly.

#include <string>
#include <utility>
#include <vector>

namespace incise {

/// Where and with what a run happened. Every field is a human-readable string; "unknown" when
/// the platform does not tell.
struct RunEnvironment {
  std::string date_utc;    ///< capture time, ISO 8601 UTC, e.g. "2026-12-02T14:05:09Z"
  std::string host;        ///< gethostname()
  std::string cpu;         ///< /proc/cpuinfo "model name" of the first processor
  std::string cores;       ///< std::thread::hardware_concurrency()
  std::string compiler;    ///< compiler family and version the library was built with
  std::string build_type;  ///< CMake configuration of the library build (Release, Debug, ...)
  std::string blas;        ///< path of the BLAS shared object mapped into this process (from
                           ///< /proc/self/maps: what CHOLMOD calls at run time), or "none loaded"
  std::string eigen;       ///< Eigen version

  /// The fields as (key, value) pairs in a fixed order, keys as above; for writers (JSON, HTML).
  std::vector<std::pair<std::string, std::string>> fields() const;
};

/// Reads the environment now (cheap: a few small /proc reads).
RunEnvironment capture_environment();

/// /proc/cpuinfo's value for `key` of the first processor that has it ("" when absent).
std::string cpuinfo_field(const std::string& key);

/// Path of the BLAS shared object mapped into this process, or "none loaded".
std::string loaded_blas();

}  // namespace incise
