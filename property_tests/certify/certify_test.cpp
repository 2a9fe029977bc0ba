// The certification catalogue's one judging mechanism (lib/src/scene/certify.cpp, docs/scenes.md
// "incise certify"): a check passes iff its bound exists in tolerances.json, its measurement
// throws nothing, its side conditions hold and value <= bound.

#include <incise/certify/certify.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include "incise_test/seed.hpp"

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

/// A reference_data folder whose certify/tolerances.json holds `checks`.
std::string data_dir_with(const Json& checks, const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("incise_certify_test_" + name);
  fs::create_directories(dir / "certify");
  std::ofstream(dir / "certify" / "tolerances.json") << Json{{"checks", checks}}.dump();
  return dir.string();
}

TEST(Certify, CatalogueIdsUniqueAndEveryCheckHasAStoredBound) {
  std::ifstream in(incise::test::source_path("reference_data/certify/tolerances.json"));
  const Json tol = Json::parse(in).at("checks");
  std::set<std::string> ids;
  for (const auto& c : incise::certify::certify_catalogue()) {
    EXPECT_TRUE(ids.insert(c.id).second) << "duplicate id " << c.id;
    EXPECT_FALSE(c.source.empty()) << c.id;
    EXPECT_FALSE(c.comparison.empty()) << c.id;
    ASSERT_TRUE(tol.contains(c.id)) << c.id;
    EXPECT_TRUE(tol[c.id].contains(c.tolerance_name)) << c.id << "." << c.tolerance_name;
    EXPECT_TRUE(tol[c.id].contains("why")) << c.id << ": a bound needs its justification";
  }
}

TEST(Certify, PassesWithinTheStoredBound) {
  const auto dir = data_dir_with({{"box_volume", {{"relative", 1e-13}}}}, "pass");
  const auto s = incise::certify::run_certify(dir, true, "^box_volume$");
  ASSERT_EQ(s.results.size(), 1u);
  EXPECT_TRUE(s.results[0].passed) << s.results[0].detail;
  EXPECT_EQ(s.passed, 1);
  EXPECT_DOUBLE_EQ(s.results[0].tolerance, 1e-13);
}

TEST(Certify, FailsWhenTheValueExceedsTheBound) {
  // The box volumes carry round-off (~1e-14), so a zero bound must fail.
  const auto dir = data_dir_with({{"box_volume", {{"relative", 0.0}}}}, "tight");
  const auto s = incise::certify::run_certify(dir, true, "^box_volume$");
  ASSERT_EQ(s.results.size(), 1u);
  EXPECT_FALSE(s.results[0].passed);
  EXPECT_GT(s.results[0].value, 0.0);
  EXPECT_EQ(s.failed, 1);
}

TEST(Certify, MissingBoundFailsWithoutRunning) {
  const auto dir = data_dir_with(Json::object(), "missing");
  const auto s = incise::certify::run_certify(dir, true, "^box_volume$");
  ASSERT_EQ(s.results.size(), 1u);
  EXPECT_FALSE(s.results[0].passed);
  EXPECT_TRUE(std::isnan(s.results[0].value));  // never measured
  EXPECT_NE(s.results[0].detail.find("no tolerance \"relative\""), std::string::npos)
      << s.results[0].detail;
}

TEST(Certify, ExceptionInAMeasurementIsAFailure) {
  // liver_validate reads <data>/meshes/liver_coarse.mesh, absent from this folder.
  const auto dir = data_dir_with({{"liver_validate", {{"violations", 0}}}}, "exception");
  const auto s = incise::certify::run_certify(dir, true, "^liver_validate$");
  ASSERT_EQ(s.results.size(), 1u);
  EXPECT_FALSE(s.results[0].passed);
  EXPECT_NE(s.results[0].detail.find("exception:"), std::string::npos) << s.results[0].detail;
}

}  // namespace
