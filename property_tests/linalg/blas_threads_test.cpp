/// \file blas_threads_test.cpp
/// BLAS threading controlled by the library (linalg/blas_threads.hpp, docs/solvers.md "BLAS
/// threads"): the policy function, the environment overrides and their errors, the thread count
/// set around a scope (nested scopes, parking at the end), and CholmodFactor choosing one thread
/// for a small factorization and all for one above the threshold — with the same solution.

#include "random_spd.hpp"

#include <incise/core/error.hpp>
#include <incise/linalg/blas_threads.hpp>
#include <incise/linalg/cholmod_factor.hpp>
#include <incise_test/seed.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace incise::test {
namespace {

using linalg::blas_threads;
using linalg::blas_threads_for;
using linalg::parse_blas_thread_settings;
using linalg::ScopedBlasThreads;

TEST(BlasThreadPolicy, OneThreadBelowTheThresholdAllFromIt) {
  EXPECT_EQ(blas_threads_for(0.0, 4, 1e6), 1);
  EXPECT_EQ(blas_threads_for(999999.0, 4, 1e6), 1);
  EXPECT_EQ(blas_threads_for(1e6, 4, 1e6), 4);  // the threshold itself is "large"
  EXPECT_EQ(blas_threads_for(1e12, 4, 1e6), 4);
  EXPECT_EQ(blas_threads_for(1e12, 1, 1e6), 1);
  EXPECT_EQ(blas_threads_for(0.0, 3, 0.0), 3);  // threshold 0: always all threads
  EXPECT_EQ(blas_threads_for(1e3, 2, linalg::kDefaultBlasParallelFlops), 1);
}

TEST(BlasThreadPolicy, RejectsBadArguments) {
  EXPECT_THROW((void)blas_threads_for(1.0, 0, 1.0), ParameterError);
  EXPECT_THROW((void)blas_threads_for(-1.0, 2, 1.0), ParameterError);
  EXPECT_THROW((void)blas_threads_for(1.0, 2, -1.0), ParameterError);
  EXPECT_THROW((void)blas_threads_for(1.0, 2, std::nan("")), ParameterError);
}

TEST(BlasThreadSettings, DefaultsAndOverrides) {
  const auto d = parse_blas_thread_settings(nullptr, nullptr, 6);
  EXPECT_EQ(d.max_threads, 6);
  EXPECT_EQ(d.parallel_flops, linalg::kDefaultBlasParallelFlops);
  const auto capped = parse_blas_thread_settings("2", "1e9", 6);
  EXPECT_EQ(capped.max_threads, 2);
  EXPECT_EQ(capped.parallel_flops, 1e9);
  // A cap above what the BLAS started with does not raise it (OPENBLAS_NUM_THREADS rules).
  EXPECT_EQ(parse_blas_thread_settings("64", nullptr, 2).max_threads, 2);
  EXPECT_EQ(parse_blas_thread_settings(nullptr, "0", 2).parallel_flops, 0.0);
}

void expect_error_naming(const char* threads, const char* flops, const std::string& what) {
  try {
    (void)parse_blas_thread_settings(threads, flops, 2);
    ADD_FAILURE() << "no error for " << (threads ? threads : "-") << " / " << (flops ? flops : "-");
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
  }
}

TEST(BlasThreadSettings, BadEnvironmentValuesNameTheVariable) {
  for (const char* bad : {"0", "-1", "2x", "", "1.5", "99999"})
    expect_error_naming(bad, nullptr, std::string("INCISE_BLAS_THREADS = \"") + bad + "\"");
  for (const char* bad : {"-1", "abc", "1e9x", "nan", "inf", ""})
    expect_error_naming(nullptr, bad, std::string("INCISE_BLAS_PARALLEL_FLOPS = \"") + bad + "\"");
}

// The count in force is the largest live request, capped at max_threads; parking at the end of
// the last scope sets one thread again. Without a controllable BLAS every count reads 1.
TEST(ScopedBlasThreads, SetsTheCountAroundACallAndParksAfterwards) {
  const int max = linalg::blas_thread_settings().max_threads;
  linalg::park_blas_threads();
  EXPECT_EQ(blas_threads(), 1);
  {
    const ScopedBlasThreads wide(2);
    EXPECT_EQ(wide.threads(), std::min(2, max));
    if (linalg::blas_thread_control_available()) {
      EXPECT_EQ(blas_threads(), wide.threads());
    }
    {
      const ScopedBlasThreads narrow(1);
      EXPECT_EQ(narrow.threads(), 1);
      // the wider live request still rules
      if (linalg::blas_thread_control_available()) {
        EXPECT_EQ(blas_threads(), wide.threads());
      }
    }
    if (linalg::blas_thread_control_available()) {
      EXPECT_EQ(blas_threads(), wide.threads());
    }
  }
  EXPECT_EQ(blas_threads(), 1);
  {
    const ScopedBlasThreads big(1000);
    EXPECT_EQ(big.threads(), max);  // capped
  }
  EXPECT_EQ(blas_threads(), 1);
  EXPECT_THROW(ScopedBlasThreads(0), ParameterError);
}

TEST(ScopedBlasThreads, CholmodFactorUsesOneThreadBelowTheThresholdAndAllAbove) {
  INCISE_SEEDED_RNG(rng, 20261202);
  const linalg::SparseMatrix a = random_sparse_spd(2000, 6, 0.1, rng);
  Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(a.rows(), -1.0, 1.0);
  Eigen::VectorXd x_small, x_large;
  linalg::CholmodOptions small_opts;
  small_opts.blas_parallel_flops = 1e300;  // everything is "small"
  linalg::CholmodFactor small(small_opts);
  EXPECT_EQ(small.last_blas_threads(), 0);  // before any factorization
  ASSERT_EQ(small.compute(a, 1), linalg::FactorStatus::kOk);
  EXPECT_EQ(small.last_blas_threads(), 1);
  EXPECT_EQ(blas_threads(), 1);  // parked after the call
  ASSERT_EQ(small.solve(b, x_small), linalg::FactorStatus::kOk);

  linalg::CholmodOptions large_opts;
  large_opts.blas_parallel_flops = 0.0;  // everything is "large"
  linalg::CholmodFactor large(large_opts);
  ASSERT_EQ(large.compute(a, 1), linalg::FactorStatus::kOk);
  EXPECT_EQ(large.last_blas_threads(), linalg::blas_thread_settings().max_threads);
  EXPECT_EQ(blas_threads(), 1);  // parked after the call
  ASSERT_EQ(large.solve(b, x_large), linalg::FactorStatus::kOk);
  // Same matrix, same analysis; only the BLAS's summation order may differ between thread
  // counts: κ ≲ 1e3 for this matrix (random_spd.hpp), so 1e-10 relative bounds it with margin.
  EXPECT_LE((x_small - x_large).norm(), 1e-10 * x_small.norm());
  EXPECT_LE((a * x_large - b).norm(), 1e-9 * b.norm());

  linalg::CholmodOptions nan_opts;
  nan_opts.blas_parallel_flops = std::nan("");
  EXPECT_THROW(linalg::CholmodFactor{nan_opts}, ParameterError);
}

}  // namespace
}  // namespace incise::test
