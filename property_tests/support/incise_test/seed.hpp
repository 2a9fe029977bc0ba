#pragma once
/// \file seed.hpp
/// Deterministic seeds for randomized tests. The seed is fixed (default per test) and can be
/// overridden with the environment variable INCISE_SEED; it is attached to every failure message
/// through a gtest scoped trace, so a failing run can be reproduced exactly.

#include <incise/core/error.hpp>

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <string>

namespace incise::test {

/// The seed for this test: INCISE_SEED if set (decimal), else `default_seed`.
std::uint64_t seed(std::uint64_t default_seed = 20031107);

/// Absolute path of a file under the source tree (INCISE_SOURCE_DIR env, else compile-time root).
std::string source_path(const std::string& relative);

/// Number of repetitions scaled by INCISE_TEST_SCALE (default 1.0; e.g. 10 for soak runs).
int scaled(int n);

/// scaled(n) in optimized builds; scaled(n / divisor) (at least 1) in builds with debug checks
/// (Debug, and the sanitizer presets, which set INCISE_PARANOID: the connectivity validates
/// itself after every edit, O(n) each, so long random sequences become quadratic there).
inline int scaled_for_checks(int n, int divisor = 10) {
#if INCISE_DEBUG_CHECKS
  return scaled(n / divisor > 0 ? n / divisor : 1);
#else
  (void)divisor;
  return scaled(n);
#endif
}

/// Whether the environment variable `name` is set: how the slow variants of tests (ctest label
/// slow, set by their add_test ENVIRONMENT) ask for their longer runs.
bool env_set(const char* name);

/// How often a long random edit sequence calls its own full validate(): after every edit in
/// plain builds, every 20th with INCISE_PARANOID (the connectivity then already runs the
/// structural validate() after every edit itself; connectivity.hpp).
#ifdef INCISE_PARANOID
inline constexpr int kValidateEvery = 20;
#else
inline constexpr int kValidateEvery = 1;
#endif

}  // namespace incise::test

/// Declare a std::mt19937_64 named `rng` seeded by incise::test::seed(default) and print the seed
/// on any failure in the enclosing scope.
#define INCISE_SEEDED_RNG(rng, default_seed)                                         \
  const std::uint64_t rng##_seed = ::incise::test::seed(default_seed);               \
  SCOPED_TRACE("seed = " + std::to_string(rng##_seed) + " (override: INCISE_SEED)"); \
  std::mt19937_64 rng(rng##_seed)
