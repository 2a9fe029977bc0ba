// The certification catalogue's one judging mechanism (lib/src/certify/certify.cpp,
// docs/certify.md): a check passes iff its bands exist in tolerances.json, its measurement throws
// nothing, its side conditions hold and every comparison lies in its band [min, max]; and the
// sizing of cg_vs_cholmod: a 1 % stiffness error anywhere moves its answer far out of the band.

#include <incise/certify/certify.hpp>
#include <incise/fem/elastic_problem.hpp>
#include <incise/fem/stiffness.hpp>
#include <incise/linalg/cholmod_factor.hpp>
#include <incise/material/material.hpp>
#include <incise/scene/scene_builder.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include "incise_test/seed.hpp"

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;
using incise::certify::run_certify;

/// A reference_data folder whose certify/tolerances.json holds `checks`.
std::string data_dir_with(const Json& checks, const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("incise_certify_test_" + name);
  fs::create_directories(dir / "certify");
  std::ofstream(dir / "certify" / "tolerances.json") << Json{{"checks", checks}}.dump();
  return dir.string();
}

Json band(double lo, double hi) {
  return Json{{"band", {lo, hi}}, {"why", "test"}};
}

Json stored_tolerances() {
  std::ifstream in(incise::test::source_path("reference_data/certify/tolerances.json"));
  return Json::parse(in).at("checks");
}

TEST(Certify, CatalogueIdsUniqueAndEveryBandStoredWithItsJustification) {
  const Json tol = stored_tolerances();
  std::set<std::string> ids;
  for (const auto& c : incise::certify::certify_catalogue()) {
    EXPECT_TRUE(ids.insert(c.id).second) << "duplicate id " << c.id;
    EXPECT_FALSE(c.source.empty()) << c.id;
    EXPECT_FALSE(c.criterion.empty()) << c.id;
    EXPECT_FALSE(c.bands.empty()) << c.id;
    ASSERT_TRUE(tol.contains(c.id)) << c.id;
    incise::certify::CertifyContext ctx;
    ctx.tolerances = tol;
    for (const std::string& b : c.bands) {
      EXPECT_NO_THROW((void)ctx.band(c.id, b)) << c.id << "." << b;
      EXPECT_GE(ctx.why(c.id, b).size(), 40u) << c.id << "." << b << ": justify the band";
    }
  }
  for (const auto& [id, bands] : tol.items()) EXPECT_TRUE(ids.count(id)) << "stale entry " << id;
}

TEST(Certify, BandIsClosedAndRejectsNaN) {
  const incise::certify::Band b{1.0, 2.0};
  EXPECT_TRUE(b.contains(1.0));
  EXPECT_TRUE(b.contains(2.0));
  EXPECT_FALSE(b.contains(0.999));
  EXPECT_FALSE(b.contains(2.001));
  EXPECT_FALSE(b.contains(std::numeric_limits<double>::quiet_NaN()));
}

TEST(Certify, PassesWithinTheStoredBand) {
  const auto dir = data_dir_with({{"box_volume", {{"relative", band(0, 1e-13)}}}}, "pass");
  const auto s = run_certify(dir, true, "^box_volume$");
  ASSERT_EQ(s.results.size(), 1u);
  EXPECT_TRUE(s.results[0].passed) << s.results[0].detail;
  EXPECT_EQ(s.passed, 1);
  ASSERT_FALSE(s.results[0].comparisons.empty());
  EXPECT_EQ(s.results[0].comparisons[0].bounds.max, 1e-13);
  EXPECT_EQ(s.results[0].failed_comparisons(), 0);
}

TEST(Certify, ReportsRecordTheCommitAndTheRunEnvironment) {
  const auto dir = data_dir_with({{"box_volume", {{"relative", band(0, 1e-13)}}}}, "env");
  const auto s = run_certify(dir, true, "^box_volume$");
  const Json j = incise::certify::certify_json(s, "abc123");
  EXPECT_EQ(j.at("commit"), "abc123");
  const std::string html = incise::certify::certify_html(s, "abc123");
  EXPECT_NE(html.find("<table id=\"environment\">"), std::string::npos);
  for (const auto& [key, value] : s.environment.fields()) {
    EXPECT_FALSE(value.empty()) << key;
    EXPECT_EQ(j.at("environment").at(key), value) << key;
    EXPECT_NE(html.find("<th>" + key + "</th>"), std::string::npos) << key;
  }
}

TEST(Certify, FailsAboveTheBand) {
  // The box volumes carry round-off (~1e-14) on the larger boxes, so [0, 0] must fail.
  const auto dir = data_dir_with({{"box_volume", {{"relative", band(0, 0)}}}}, "above");
  const auto s = run_certify(dir, true, "^box_volume$");
  ASSERT_EQ(s.results.size(), 1u);
  EXPECT_FALSE(s.results[0].passed);
  EXPECT_GT(s.results[0].failed_comparisons(), 0);
  EXPECT_EQ(s.failed, 1);
}

TEST(Certify, FailsBelowTheBand) {
  // Two-sided: errors far below the band's lower end fail as well.
  const auto dir = data_dir_with({{"box_volume", {{"relative", band(1e-3, 1)}}}}, "below");
  const auto s = run_certify(dir, true, "^box_volume$");
  ASSERT_EQ(s.results.size(), 1u);
  EXPECT_FALSE(s.results[0].passed);
  const auto* h = s.results[0].headline();
  ASSERT_NE(h, nullptr);
  EXPECT_FALSE(h->passed);
  EXPECT_LT(h->value, 1e-3);
  EXPECT_LT(h->margin, 0.0);
}

TEST(Certify, MissingOrMalformedBandFailsWithoutRunning) {
  const Json cases[] = {
      Json::object(),                                                          // no entry
      {{"box_volume", {{"relative", 1e-13}}}},                                 // bare number
      {{"box_volume", {{"relative", {{"band", {1.0, 0.0}}, {"why", "x"}}}}}},  // min > max
      {{"box_volume", {{"relative", {{"band", {0.0, 1.0}}}}}}},                // no justification
  };
  int k = 0;
  for (const Json& c : cases) {
    const auto dir = data_dir_with(c, "missing" + std::to_string(k++));
    const auto s = run_certify(dir, true, "^box_volume$");
    ASSERT_EQ(s.results.size(), 1u);
    EXPECT_FALSE(s.results[0].passed) << c.dump();
    EXPECT_TRUE(s.results[0].comparisons.empty()) << "never measured: " << c.dump();
    EXPECT_NE(s.results[0].detail.find("band \"relative\""), std::string::npos)
        << s.results[0].detail;
  }
}

TEST(Certify, ExceptionInAMeasurementIsAFailure) {
  // liver_validate reads <data>/meshes/liver_coarse.mesh, absent from this folder.
  const auto dir = data_dir_with({{"liver_validate", {{"violations", band(0, 0)}}}}, "exception");
  const auto s = run_certify(dir, true, "^liver_validate$");
  ASSERT_EQ(s.results.size(), 1u);
  EXPECT_FALSE(s.results[0].passed);
  EXPECT_NE(s.results[0].detail.find("exception:"), std::string::npos) << s.results[0].detail;
}

TEST(Certify, ShippedScenesProbeWithAReferenceNeedsABand) {
  // A data folder holding only the cantilever scene, whose tip probe has a reference: with the
  // stored bands it passes; without the probe's band that comparison fails.
  const Json stored = stored_tolerances().at("shipped_scenes");
  Json without = stored;
  without.erase("probe cantilever.json tip");
  int k = 0;
  for (const Json& bands : {stored, without}) {
    const auto dir = data_dir_with({{"shipped_scenes", bands}}, "probe" + std::to_string(k++));
    fs::create_directories(fs::path(dir) / "scenes");
    fs::copy_file(incise::test::source_path("reference_data/scenes/cantilever.json"),
                  fs::path(dir) / "scenes" / "cantilever.json",
                  fs::copy_options::overwrite_existing);
    const auto s = run_certify(dir, true, "^shipped_scenes$");
    ASSERT_EQ(s.results.size(), 1u);
    EXPECT_EQ(s.results[0].passed, bands == stored) << s.results[0].detail;
    bool probe_compared = false;
    for (const auto& c : s.results[0].comparisons)
      if (c.band == "probe cantilever.json tip") {
        probe_compared = true;
        EXPECT_EQ(c.passed, bands == stored);
        EXPECT_NEAR(c.value, 0.233, 0.005);  // the relative tip error, docs/scenes.md
      }
    EXPECT_TRUE(probe_compared);
  }
}

// cg_vs_cholmod compares CG (which converges to the solution of the element forces) with CHOLMOD
// on the assembled K. A 1 % error in the stiffness of any single element — or in the λ part of
// it alone, which ν = 0 would hide — must move the CHOLMOD answer far beyond the check's band
// on the quick mesh (the λ part: on 99 % of the elements). First order: (K + 0.01 P_e) (u + du) = f
// gives du = −K⁻¹ (0.01 P_e u).
TEST(CertifyCgVsCholmod, OnePercentErrorInAnyElementsStiffnessIsFarOutsideTheBand) {
  incise::certify::CertifyContext ctx;
  ctx.tolerances = stored_tolerances();
  const double band_max = ctx.band("cg_vs_cholmod", "relative").max;
  incise::scene::BuiltScene b =
      incise::scene::build_scene(incise::certify::cg_vs_cholmod_scene(true));
  incise::fem::ElasticProblem& p = *b.problem;
  ASSERT_NE(p.num_elements() % 4, 0) << "the mesh must exercise the scalar tail";
  const incise::VecX zero = incise::VecX::Zero(p.size());
  ASSERT_EQ(p.assemble_tangent(zero, incise::fem::FixedDofTreatment::kIdentity),
            incise::EvalStatus::kOk);
  incise::linalg::CholmodFactor factor;
  ASSERT_EQ(factor.compute(p.tangent_matrix(), 1), incise::linalg::FactorStatus::kOk);
  incise::VecX f = p.external_force(), u;
  p.project(f);
  ASSERT_EQ(factor.solve(f, u), incise::linalg::FactorStatus::kOk);
  // The μ part of the element stiffness: the same shear modulus with ν = 0 (λ = 0).
  const incise::material::Material& mat = p.material();
  incise::material::Parameters mu_only = mat.parameters();
  mu_only.youngs_modulus = 2 * mat.lame().mu;
  mu_only.poisson_ratio = 0.0;
  const incise::material::Material shear(mat.name(), mu_only);
  double min_whole = 1e300;
  std::vector<double> all_lambda;
  for (incise::Index e = 0; e < p.num_elements(); ++e) {
    incise::fem::Mat34T<double> x, ue;
    for (int a = 0; a < 4; ++a) {
      const incise::Index v = p.cells()(a, e);
      x.col(a) = p.points().col(v);
      ue.col(a) = u.segment<3>(3 * v);
    }
    incise::fem::Mat12T<double> k_e, k_mu;
    const incise::fem::Mat34T<double> u0 = incise::fem::Mat34T<double>::Zero();
    ASSERT_TRUE(incise::fem::element_stiffness(mat, x, u0, k_e));
    ASSERT_TRUE(incise::fem::element_stiffness(shear, x, u0, k_mu));
    const Eigen::Matrix<double, 12, 1> ue_vec =
        Eigen::Map<const Eigen::Matrix<double, 12, 1>>(ue.data());
    for (int which = 0; which < 2; ++which) {
      const Eigen::Matrix<double, 12, 1> df = 0.01 * (which == 0 ? k_e : k_e - k_mu) * ue_vec;
      incise::VecX rhs = incise::VecX::Zero(p.size()), du;
      for (int a = 0; a < 4; ++a) rhs.segment<3>(3 * p.cells()(a, e)) += df.segment<3>(3 * a);
      p.project(rhs);
      ASSERT_EQ(factor.solve(rhs, du), incise::linalg::FactorStatus::kOk);
      if (which == 0) {
        min_whole = std::min(min_whole, du.norm() / u.norm());
      } else {
        all_lambda.push_back(du.norm() / u.norm());
      }
    }
  }
  // Every element: > 100x the band. The λ part alone (zero at ν = 0): > 10x the band for 99 % of
  // the elements (the rest carry almost no volumetric strain in this bending problem).
  std::sort(all_lambda.begin(), all_lambda.end());
  const double lambda_p01 = all_lambda[all_lambda.size() / 100];
  EXPECT_GT(min_whole, 100 * band_max) << "smallest effect of a 1 % element stiffness error";
  EXPECT_GT(lambda_p01, 10 * band_max) << "1 % quantile, 1 % error in the lambda part";
  std::cout << "cg_vs_cholmod quick mesh (" << p.num_elements()
            << " tets): smallest ||du||/||u|| of a 1 % error in one element's K_e " << min_whole
            << "; of a 1 % error in its lambda part: 1 % quantile " << lambda_p01 << ", median "
            << all_lambda[all_lambda.size() / 2] << " (band max " << band_max << ")\n";
}

}  // namespace
