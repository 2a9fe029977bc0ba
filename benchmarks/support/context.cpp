#include "incise_bench/context.hpp"

#include <incise/core/baseline.hpp>
#include <incise/core/environment.hpp>

#include <benchmark/benchmark.h>

#include <sstream>

namespace incise::bench {

double vector_add_mflops() {
  return incise::vector_add_mflops();  // lib/src/core/baseline.cpp, one implementation
}

double fma_peak_mflops() {
  const std::string mhz = incise::cpuinfo_field("cpu MHz");
  const std::string flags = incise::cpuinfo_field("flags");
  if (mhz.empty()) return 0.0;
  double per_cycle = 4.0;  // SSE2: 2-wide add + 2-wide mul
  if (flags.find(" avx512f") != std::string::npos)
    per_cycle = 32.0;
  else if (flags.find(" fma") != std::string::npos && flags.find(" avx2") != std::string::npos)
    per_cycle = 16.0;  // two 4-wide FMA units
  else if (flags.find(" avx") != std::string::npos)
    per_cycle = 8.0;
  return std::stod(mhz) * per_cycle;
}

void add_context() {
  // The same record as every incise report (core/environment.hpp), keys prefixed "incise_".
  for (const auto& [key, value] : incise::capture_environment().fields())
    if (key != "date_utc" && key != "host" && key != "cores")  // Google Benchmark records those
      benchmark::AddCustomContext("incise_" + key, value);
  std::ostringstream base, peak;
  base << vector_add_mflops();
  peak << fma_peak_mflops();
  benchmark::AddCustomContext("incise_vector_add_mflops", base.str());
  benchmark::AddCustomContext("incise_fma_peak_mflops_nominal", peak.str());
}

}  // namespace incise::bench
