// The mutation test of `incise certify` (docs/certify.md, "Mutation test"): each
// mutations/<id>.mutation breaks one library source in a copy linked into certify_mutant_<id>
// (CMakeLists.txt); running the quick catalogue there must turn exactly the checks of its row in
// kExpected red, and every check of the catalogue must turn red under at least one mutation. The
// table is the one in docs/certify.md.

#include <incise/certify/certify.hpp>

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <string>

#include "incise_test/seed.hpp"

namespace {

/// Mutation id → the checks of the quick catalogue it turns red.
const std::map<std::string, std::set<std::string>> kExpected = {
    {"none", {}},
    {"box_spacing", {"box_volume", "shipped_scenes", "patch_test", "cantilever_table_3_1"}},
    {"cylinder_radius", {"cylinder_volume"}},
    {"mesh_reader_pinched", {"liver_validate"}},
    {"element_volume",
     {"shipped_scenes", "patch_test", "cantilever_table_3_1", "augmented_cut_vs_cut_first"}},
    {"matrix_free_product", {"matrix_free_vs_assembled", "cantilever_table_3_1"}},
    {"assembly_tail", {"matrix_free_vs_assembled", "cg_vs_cholmod"}},
    {"lame_lambda", {"patch_test"}},
    {"flop_count_kernel", {"flop_table_4_3"}},
    {"flop_accounting", {"performance_table_4_5"}},
    {"stopping_rule",
     {"shipped_scenes", "cantilever_table_3_1", "cg_vs_cholmod", "solver_equivalence_cylinder"}},
};

struct MutantRun {
  bool started = false;
  int status = -1;
  std::string output;
  std::map<std::string, bool> passed;  ///< check id → passed
};

/// Runs certify_mutant_<id> on the source tree's reference_data.
MutantRun run_mutant(const std::string& id) {
  MutantRun r;
  const std::string cmd = std::string(INCISE_MUTANT_DIR) + "/certify_mutant_" + id + " '" +
                          incise::test::source_path("reference_data") + "' 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return r;
  r.started = true;
  char buf[4096];
  while (fgets(buf, sizeof buf, p)) r.output += buf;
  r.status = pclose(p);
  std::size_t start = 0;
  while (start < r.output.size()) {
    const std::size_t end = r.output.find('\n', start);
    const std::string line =
        r.output.substr(start, end == std::string::npos ? std::string::npos : end - start);
    start = end == std::string::npos ? r.output.size() : end + 1;
    const std::size_t sp = line.rfind(' ');
    if (line.empty() || line[0] == '#' || sp == std::string::npos) continue;
    const std::string verdict = line.substr(sp + 1);
    if (verdict == "PASS" || verdict == "FAIL") r.passed[line.substr(0, sp)] = verdict == "PASS";
  }
  return r;
}

class CertifyMutation : public ::testing::TestWithParam<std::string> {};

TEST_P(CertifyMutation, TurnsExactlyItsChecksRed) {
  const std::string id = GetParam();
  const MutantRun r = run_mutant(id);
  ASSERT_TRUE(r.started);
  ASSERT_EQ(r.status, 0) << r.output;
  std::set<std::string> red;
  for (const auto& c : incise::certify::certify_catalogue()) {
    ASSERT_TRUE(r.passed.count(c.id)) << "check " << c.id << " missing in:\n" << r.output;
    if (!r.passed.at(c.id)) red.insert(c.id);
  }
  EXPECT_EQ(red, kExpected.at(id)) << "mutation " << id << ", output:\n" << r.output;
}

std::vector<std::string> mutation_ids() {
  std::vector<std::string> ids;
  for (const auto& kv : kExpected) ids.push_back(kv.first);
  return ids;
}

std::string mutation_name(const ::testing::TestParamInfo<std::string>& p) {
  return p.param;
}

INSTANTIATE_TEST_SUITE_P(Mutants, CertifyMutation, ::testing::ValuesIn(mutation_ids()),
                         mutation_name);

TEST(CertifyMutationTable, EveryCheckTurnsRedUnderSomeMutationAndEverySpecHasARow) {
  std::set<std::string> caught;
  for (const auto& [id, red] : kExpected) {
    if (id != "none") {
      EXPECT_FALSE(red.empty()) << "mutation " << id << " is caught by no check";
    }
    caught.insert(red.begin(), red.end());
  }
  for (const auto& c : incise::certify::certify_catalogue())
    EXPECT_TRUE(caught.count(c.id)) << "no mutation turns check " << c.id << " red";
  std::set<std::string> specs;
  for (const auto& e : std::filesystem::directory_iterator(
           incise::test::source_path("property_tests/certify/mutations")))
    if (e.path().extension() == ".mutation") specs.insert(e.path().stem().string());
  std::set<std::string> rows;
  for (const auto& kv : kExpected)
    if (kv.first != "none") rows.insert(kv.first);
  EXPECT_EQ(specs, rows) << "mutations/*.mutation and kExpected must list the same mutations";
}

}  // namespace
