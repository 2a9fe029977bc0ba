#include <incise/core/memory_budget.hpp>

#include <unistd.h>

#include <fstream>
#include <sstream>
#include <string>

namespace incise {

std::uint64_t physical_memory_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long page = sysconf(_SC_PAGESIZE);
  if (pages > 0 && page > 0)
    return static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page);
  std::ifstream in("/proc/meminfo");
  for (std::string line; std::getline(in, line);) {
    std::istringstream row(line);
    std::string key;
    std::uint64_t kib = 0;
    if (row >> key >> kib && key == "MemTotal:") return kib * 1024;  // "MemTotal: N kB"
  }
  return 0;
}

std::uint64_t default_memory_budget_bytes() {
  const std::uint64_t physical = physical_memory_bytes();
  return physical > 0
             ? static_cast<std::uint64_t>(kDefaultMemoryFraction * static_cast<double>(physical))
             : kFallbackMemoryBudget;
}

}  // namespace incise
