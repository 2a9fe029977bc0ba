// RunEnvironment (core/environment.hpp): every field filled, in the documented form.

#include <incise/core/environment.hpp>
#include <incise/linalg/cholmod_factor.hpp>

#include <gtest/gtest.h>

#include <regex>
#include <string>

namespace incise {
namespace {

TEST(RunEnvironment, EveryFieldIsFilledInItsDocumentedForm) {
  const RunEnvironment e = capture_environment();
  EXPECT_TRUE(std::regex_match(e.date_utc, std::regex(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ)")))
      << e.date_utc;
  EXPECT_GT(std::stoi(e.cores), 0);
  EXPECT_TRUE(std::regex_match(e.eigen, std::regex(R"(\d+\.\d+\.\d+)"))) << e.eigen;
  EXPECT_TRUE(e.compiler.rfind("g++ ", 0) == 0 || e.compiler.rfind("clang ", 0) == 0) << e.compiler;
  EXPECT_NE(e.build_type, "unknown");  // set by lib/src/core/CMakeLists.txt for every build
  const auto fields = e.fields();
  ASSERT_EQ(fields.size(), 8u);
  EXPECT_EQ(fields.front().first, "date_utc");
  for (const auto& [key, value] : fields) EXPECT_FALSE(value.empty()) << key;
}

TEST(RunEnvironment, FindsTheBlasCholmodLoads) {
  // Factor a small SPD system so that CHOLMOD (linked here) is certainly mapped with its BLAS.
  Eigen::SparseMatrix<double> a(3, 3);
  for (int i = 0; i < 3; ++i) {
    a.insert(i, i) = 2.0;
    if (i > 0) a.insert(i, i - 1) = -1.0;  // lower triangle only is read
  }
  a.makeCompressed();
  linalg::CholmodFactor f;
  ASSERT_EQ(f.compute(a, 1), linalg::FactorStatus::kOk);
  const std::string blas = loaded_blas();
  EXPECT_NE(blas.find("blas"), std::string::npos) << blas;
  EXPECT_EQ(blas.front(), '/') << blas;
}

TEST(RunEnvironment, CpuinfoFieldOfAnAbsentKeyIsEmpty) {
  EXPECT_EQ(cpuinfo_field("no such key in cpuinfo"), "");
}

}  // namespace
}  // namespace incise
