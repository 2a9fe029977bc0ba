// The `incise certify` catalogue (certify.hpp): the check table (one row per check: what it
// reproduces from the thesis / Yeung et al. 2016, its criterion, the name of its bound in
// reference_data/certify/tolerances.json, its measurement) and run_certify, which runs the
// measurements and judges them. The measurements live in certify_<area>.cpp (list in
// certify_checks.hpp); the HTML / JSON rendering in certify_report.cpp.

#include <incise/certify/certify.hpp>

#include <incise/core/error.hpp>
#include <incise/core/timer.hpp>

#include <fstream>
#include <limits>
#include <regex>

#include "certify_checks.hpp"

namespace incise::certify {

double CertifyContext::tolerance(const std::string& id, const std::string& name) const {
  if (!tolerances.contains(id) || !tolerances[id].contains(name) ||
      !tolerances[id][name].is_number())
    throw Error("no tolerance \"" + name + "\" for check \"" + id +
                "\" in reference_data/certify/tolerances.json");
  return tolerances[id][name].get<double>();
}

std::string CertifyContext::why(const std::string& id) const {
  if (tolerances.contains(id) && tolerances[id].contains("why") &&
      tolerances[id]["why"].is_string())
    return tolerances[id]["why"].get<std::string>();
  return "";
}

const std::vector<Check>& certify_catalogue() {
  // One row per check: id, title, what it reproduces, the criterion, the name of its bound in
  // reference_data/certify/tolerances.json, and the measurement. run_certify() judges.
  static const std::vector<Check> kCatalogue = {
      {"box_volume", "Box generator: volumes exact",
       "generators.hpp make_box; thesis §3.3 cantilever mesh",
       "max |sum of tet volumes - lx ly lz| / (lx ly lz) <= tolerance, all volumes > 0", "relative",
       detail::measure_box_volume},
      {"cylinder_volume", "Cylinder generator: volume of the polygonal prism",
       "generators.hpp make_cylinder (thesis §4.2 cylinder, Table 4.2)",
       "max relative error against the inscribed 6k-gon prism volume <= tolerance, all volumes > 0",
       "relative", detail::measure_cylinder_volume},
      {"liver_validate", "Liver mesh: connectivity invariants (7.1)-(7.5)",
       "thesis §7.2-7.3 invariants (7.1)-(7.5); reference_data/meshes/liver_coarse.mesh",
       "number of violated invariants <= tolerance", "violations", detail::measure_liver_validate},
      {"shipped_scenes", "Shipped scenes parse and build", "docs/scenes.md; reference_data/scenes/",
       "scenes failing to parse or build <= tolerance", "failures", detail::measure_shipped_scenes},
      {"patch_test", "Patch test: homogeneous deformations, every material",
       "thesis §3.3 (deformation test), homogeneous deformations for every material",
       "max |interior nodal force| / max |nodal force| <= tolerance", "relative",
       detail::measure_patch_test},
      {"matrix_free_vs_assembled", "Matrix-free K.d equals assembled K.d",
       "thesis §3.1 matrix-free K d vs assembled K (design.md §3 equivalences)",
       "max ||K_mf d - K_asm d|| / ||K_asm d|| <= tolerance", "relative",
       detail::measure_matrix_free},
      {"flop_table_4_3", "Flops per element vs thesis Table 4.3",
       "thesis §4.3, Table 4.3 (hand counts, reference values)",
       "max over models of max(ours/thesis, thesis/ours) <= tolerance", "ratio_bound",
       detail::measure_flop_table},
      {"cantilever_table_3_1", "Cantilever tip deflection vs thesis Table 3.1",
       "thesis §3.3, Table 3.1 (l = 1.2, h = 0.2, d = 0.3 m, E = 1e6 Pa, nu = 0, F = 3 N)",
       "max over meshes of (our avg tip error - thesis avg error) in % points <= tolerance; errors "
       "positive (FEM stiffer) and decreasing",
       "excess_percent_points", detail::measure_cantilever},
      {"cg_vs_cholmod", "Linear CG equals CHOLMOD direct solve",
       "design.md §3 equivalence: CG == CHOLMOD (the augmented method's initial solve)",
       "||u_cg - u_cholmod|| / ||u_cholmod|| <= tolerance, both converged", "relative",
       detail::measure_cg_vs_cholmod},
      {"solver_equivalence_cylinder",
       "Nonlinear CG and dynamic relaxation reach the Newton minimizer (speed/accuracy)",
       "thesis §4.2-4.5: nonlinear CG and dynamic relaxation (SS22) on the cylinder under "
       "gravity, neo-Hookean, Table 4.1 parameters; reference by truncated Newton",
       "max ||u - u_newton|| / ||u_newton|| over methods <= tolerance, all converged", "relative",
       detail::measure_solver_trade},
      {"augmented_cut_vs_cut_first",
       "Interactive cut with the augmented solver equals cutting first and solving",
       "Yeung, Crouch & Pothen 2016 §3 (augmented updates) on thesis §3.2 cuts; "
       "reference_data/scenes/cube_cut_augmented.json",
       "||u_augmented - u_cg|| / ||u_cg|| <= tolerance; same cut mesh, every step solved with the "
       "initial factor (no refactorization), both converged",
       "relative", detail::measure_augmented_cut},
      {"performance_table_4_5", "Cost per iteration vs thesis Table 4.5 (machine baseline)",
       "thesis §4.5.2, Table 4.5 (MFLOP/iteration, iterations/s, % of the vector-add baseline)",
       "max over rows of max(ours/thesis, thesis/ours) of the counted MFLOP per iteration <= "
       "tolerance, every run completes its iterations; rates displayed only",
       "ratio_bound", detail::measure_table_4_5},
  };
  return kCatalogue;
}

CertifySummary run_certify(const std::string& data_dir, bool quick, const std::string& filter,
                           const std::function<void(const std::string&)>& progress) {
  const std::string tol_path = data_dir + "/certify/tolerances.json";
  std::ifstream in(tol_path);
  if (!in) throw ParseError(tol_path, 0, "cannot open the certification tolerances");
  CertifyContext ctx;
  ctx.quick = quick;
  ctx.data_dir = data_dir;
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    ctx.tolerances = j.at("checks");
  } catch (const nlohmann::json::exception& e) {
    throw ParseError(tol_path, 0, std::string("expected {\"checks\": {...}}: ") + e.what());
  }
  const std::regex re(filter.empty() ? ".*" : filter);
  CertifySummary sum;
  sum.quick = quick;
  Timer total;
  for (const Check& c : certify_catalogue()) {
    if (!std::regex_search(c.id, re)) continue;
    if (progress) progress(c.id);
    Timer t;
    CheckResult r;
    r.id = c.id;
    r.title = c.title;
    r.source = c.source;
    r.comparison = c.comparison;
    r.tolerance = std::numeric_limits<double>::quiet_NaN();
    r.value = std::numeric_limits<double>::quiet_NaN();
    try {
      // The bound first: a check without a stored tolerance fails without running.
      r.tolerance = ctx.tolerance(c.id, c.tolerance_name);
      Measurement m = c.measure(ctx);
      r.value = m.value;
      r.passed = m.conditions_ok && m.value <= r.tolerance;  // NaN value: false
      r.detail = std::move(m.detail);
      r.tables = std::move(m.tables);
      r.plots = std::move(m.plots);
    } catch (const std::exception& e) {
      r.passed = false;
      r.detail = std::string("exception: ") + e.what();
    }
    r.seconds = t.seconds();
    const std::string why = ctx.why(c.id);
    if (!why.empty()) r.detail += " Tolerance: " + why;
    (r.passed ? sum.passed : sum.failed)++;
    sum.results.push_back(std::move(r));
  }
  sum.seconds = total.seconds();
  return sum;
}

}  // namespace incise::certify
