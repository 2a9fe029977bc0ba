#include "incise_bench/context.hpp"

#include <incise/core/baseline.hpp>

#include <benchmark/benchmark.h>

#include <fstream>
#include <sstream>

namespace incise::bench {

namespace {
std::string cpuinfo_field(const std::string& key) {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.compare(0, key.size(), key) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) return line.substr(colon + 2);
    }
  }
  return "";
}
}  // namespace

double vector_add_mflops() {
  return incise::vector_add_mflops();  // lib/src/core/baseline.cpp, one implementation
}

double fma_peak_mflops() {
  const std::string mhz = cpuinfo_field("cpu MHz");
  const std::string flags = cpuinfo_field("flags");
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

std::string loaded_blas() {
  std::ifstream in("/proc/self/maps");
  std::string line;
  while (std::getline(in, line)) {
    const auto pos = line.find('/');
    if (pos == std::string::npos) continue;
    const std::string path = line.substr(pos);
    if (path.find("blas") != std::string::npos) {
      // Resolve the Debian alternatives symlink chain to the real object.
      return path;
    }
  }
  return "none loaded";
}

void add_context() {
  benchmark::AddCustomContext("incise_cpu", cpuinfo_field("model name"));
  benchmark::AddCustomContext("incise_blas", loaded_blas());
  std::ostringstream base, peak;
  base << vector_add_mflops();
  peak << fma_peak_mflops();
  benchmark::AddCustomContext("incise_vector_add_mflops", base.str());
  benchmark::AddCustomContext("incise_fma_peak_mflops_nominal", peak.str());
}

}  // namespace incise::bench
