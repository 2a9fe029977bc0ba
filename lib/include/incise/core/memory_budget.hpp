#pragma once
/// \file memory_budget.hpp
/// The default memory budget: how much memory a build planned from untrusted input (a scene's
/// generated mesh, a factorization) may claim before it allocates. Callers compare their
/// estimate with it and refuse, naming both, instead of allocating until the OOM killer.

#include <cstdint>

namespace incise {

/// Fraction of the physical memory that the default budget allows.
inline constexpr double kDefaultMemoryFraction = 0.5;

/// Budget used when the physical memory is unknown: 4 GiB.
inline constexpr std::uint64_t kFallbackMemoryBudget = std::uint64_t{4} << 30;

/// Physical memory of this machine in bytes: sysconf(_SC_PHYS_PAGES) × sysconf(_SC_PAGESIZE),
/// else MemTotal of /proc/meminfo; 0 when neither is available.
std::uint64_t physical_memory_bytes();

/// kDefaultMemoryFraction × physical_memory_bytes(), or kFallbackMemoryBudget when that is 0.
std::uint64_t default_memory_budget_bytes();

}  // namespace incise
