// RunEnvironment (environment.hpp): what a report records about the machine and the build.

#include <incise/core/environment.hpp>

#include <unistd.h>
#include <Eigen/Core>

#include <array>
#include <ctime>
#include <fstream>
#include <thread>

#ifndef INCISE_BUILD_TYPE
#define INCISE_BUILD_TYPE "unknown"
#endif

namespace incise {

std::string cpuinfo_field(const std::string& key) {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.compare(0, key.size(), key) != 0) continue;
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    const auto start = line.find_first_not_of(" \t", colon + 1);
    return start == std::string::npos ? std::string() : line.substr(start);
  }
  return "";
}

std::string loaded_blas() {
  std::ifstream in("/proc/self/maps");
  std::string line;
  while (std::getline(in, line)) {
    const auto pos = line.find('/');
    if (pos == std::string::npos) continue;
    const std::string path = line.substr(pos);
    const auto slash = path.rfind('/');
    if (path.find("blas", slash) != std::string::npos) return path;  // file name, not directory
  }
  return "none loaded";
}

namespace {

std::string compiler_name() {
#if defined(__clang__)
  return std::string("clang ") + __clang_version__;
#elif defined(__GNUC__)
  return std::string("g++ ") + __VERSION__;
#else
  return "unknown";
#endif
}

std::string or_unknown(std::string s) {
  return s.empty() ? "unknown" : s;
}

}  // namespace

std::vector<std::pair<std::string, std::string>> RunEnvironment::fields() const {
  return {{"date_utc", date_utc}, {"host", host},         {"cpu", cpu},
          {"cores", cores},       {"compiler", compiler}, {"build_type", build_type},
          {"blas", blas},         {"eigen", eigen}};
}

RunEnvironment capture_environment() {
  RunEnvironment e;
  std::array<char, 32> date{};
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  if (gmtime_r(&now, &utc) && std::strftime(date.data(), date.size(), "%Y-%m-%dT%H:%M:%SZ", &utc))
    e.date_utc = date.data();
  std::array<char, 256> host{};
  if (gethostname(host.data(), host.size() - 1) == 0) e.host = host.data();
  e.cpu = cpuinfo_field("model name");
  const unsigned n = std::thread::hardware_concurrency();
  e.cores = n ? std::to_string(n) : "";
  e.compiler = compiler_name();
  e.build_type = INCISE_BUILD_TYPE;
  e.blas = loaded_blas();
  e.eigen = std::to_string(EIGEN_WORLD_VERSION) + "." + std::to_string(EIGEN_MAJOR_VERSION) + "." +
            std::to_string(EIGEN_MINOR_VERSION);
  for (std::string* f : {&e.date_utc, &e.host, &e.cpu, &e.cores, &e.compiler, &e.build_type})
    *f = or_unknown(std::move(*f));
  return e;
}

}  // namespace incise
