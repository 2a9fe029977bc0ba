// The `incise certify` catalogue (certify.hpp, docs/certify.md): the check table (one row per
// check: what it reproduces from the thesis / Yeung et al. 2016, its criterion, the names of its
// bands in reference_data/certify/tolerances.json, its measurement) and run_certify, which runs
// the measurements and judges every comparison against its band. The measurements live in
// certify_<area>.cpp (list in certify_checks.hpp); the HTML / JSON rendering in
// certify_report.cpp.

#include <incise/certify/certify.hpp>

#include <incise/core/error.hpp>
#include <incise/core/timer.hpp>

#include <cmath>
#include <fstream>
#include <limits>
#include <regex>

#include "certify_checks.hpp"

namespace incise::certify {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

const nlohmann::json* find_band(const nlohmann::json& tolerances, const std::string& id,
                                const std::string& name) {
  if (!tolerances.contains(id) || !tolerances[id].is_object() || !tolerances[id].contains(name))
    return nullptr;
  return &tolerances[id][name];
}

/// Margin of v in b: distance to the nearer end over the width (see JudgedComparison::margin).
double band_margin(double v, const Band& b) {
  if (std::isnan(v)) return kNaN;
  const double width = b.max - b.min;
  if (width == 0.0) return b.contains(v) ? 0.0 : -std::numeric_limits<double>::infinity();
  return std::min(v - b.min, b.max - v) / width;
}

}  // namespace

Band CertifyContext::band(const std::string& id, const std::string& name) const {
  const std::string where =
      "band \"" + name + "\" of check \"" + id + "\" in reference_data/certify/tolerances.json";
  const nlohmann::json* j = find_band(tolerances, id, name);
  if (!j) throw Error("no " + where);
  if (!j->is_object() || !j->contains("band") || !(*j)["band"].is_array() ||
      (*j)["band"].size() != 2 || !(*j)["band"][0].is_number() || !(*j)["band"][1].is_number())
    throw Error(where + ": expected {\"band\": [min, max], \"why\": \"...\"}");
  if (!j->contains("why") || !(*j)["why"].is_string() || (*j)["why"].get<std::string>().empty())
    throw Error(where + ": a band needs its justification (\"why\")");
  const Band b{(*j)["band"][0].get<double>(), (*j)["band"][1].get<double>()};
  if (!std::isfinite(b.min) || !std::isfinite(b.max) || b.min > b.max)
    throw Error(where + ": expected finite min <= max");
  return b;
}

std::string CertifyContext::why(const std::string& id, const std::string& name) const {
  const nlohmann::json* j = find_band(tolerances, id, name);
  if (j && j->is_object() && j->contains("why") && (*j)["why"].is_string())
    return (*j)["why"].get<std::string>();
  return "";
}

const JudgedComparison* CheckResult::headline() const {
  const JudgedComparison* best = nullptr;
  for (const JudgedComparison& c : comparisons) {
    if (!c.passed) return &c;
    if (!best || c.margin < best->margin) best = &c;
  }
  return best;
}

int CheckResult::failed_comparisons() const {
  int n = 0;
  for (const JudgedComparison& c : comparisons) n += c.passed ? 0 : 1;
  return n;
}

const std::vector<Check>& certify_catalogue() {
  // One row per check: id, title, what it reproduces, the criterion, the names of its bands in
  // reference_data/certify/tolerances.json, and the measurement. run_certify() judges.
  static const std::vector<Check> kCatalogue = {
      {"box_volume",
       "Box generator: volumes exact",
       "generators.hpp make_box; thesis §3.3 cantilever mesh",
       "|sum of tet volumes - lx ly lz| / (lx ly lz) of every box in its band, all volumes > 0",
       {"relative"},
       detail::measure_box_volume},
      {"cylinder_volume",
       "Cylinder generator: volume of the polygonal prism",
       "generators.hpp make_cylinder (thesis §4.2 cylinder, Table 4.2)",
       "relative error against the inscribed 6k-gon prism volume in its band, all volumes > 0",
       {"relative"},
       detail::measure_cylinder_volume},
      {"liver_validate",
       "Liver mesh: connectivity invariants (7.1)-(7.5)",
       "thesis §7.2-7.3 invariants (7.1)-(7.5); reference_data/meshes/liver_coarse.mesh",
       "number of violated invariants in its band (none)",
       {"violations"},
       detail::measure_liver_validate},
      {"shipped_scenes",
       "Shipped scenes solve to their own stopping rule and references",
       "docs/scenes.md; reference_data/scenes/",
       "every scene parses, builds and solves with status ok (failures in band); its residual, "
       "recomputed here, over its own threshold tolerance ||f_ext|| in band; every probe with a "
       "reference: relative error in the band stored for it",
       {"failures", "residual_over_threshold"},
       detail::measure_shipped_scenes},
      {"patch_test",
       "Patch test: homogeneous deformations, every material",
       "thesis §3.3 (deformation test); Hooke's law (2.20) for the nodal forces",
       "u = A x: interior nodal forces vanish (|interior| / max |g| in band); every nodal force "
       "equals the consistent load of Hooke's stress on the boundary faces (exact for the "
       "linear model, to O(|A|) for the others at |A| ~ 1e-4)",
       {"interior_force", "hooke_linear", "hooke_small_strain"},
       detail::measure_patch_test},
      {"matrix_free_vs_assembled",
       "Matrix-free K.d equals assembled K.d",
       "thesis §3.1 matrix-free K d vs assembled K (design.md §3 equivalences)",
       "||K_mf d - K_asm d|| / ||K_asm d|| in its band for every material",
       {"relative"},
       detail::measure_matrix_free},
      {"flop_table_4_3",
       "Flops per element vs thesis Table 4.3",
       "thesis §4.3, Table 4.3 (hand counts, reference values)",
       "ours / thesis of every model's Force and Derivative count in its band",
       {"ratio"},
       detail::measure_flop_table},
      {"cantilever_table_3_1",
       "Cantilever tip deflection and CG iterations vs thesis Table 3.1",
       "thesis §3.3, Table 3.1 (l = 1.2, h = 0.2, d = 0.3 m, E = 1e6 Pa, nu = 0, F = 3 N)",
       "on every mesh: our compliance error over the thesis' and our CG iterations over the "
       "thesis' in their bands, CG converged; Richardson extrapolation of 1/deflection from the "
       "three finest meshes: order and limit vs Timoshenko in their bands",
       {"compliance_error_ratio", "iteration_ratio", "richardson_order",
        "richardson_vs_timoshenko"},
       detail::measure_cantilever},
      {"cg_vs_cholmod",
       "Linear CG equals CHOLMOD direct solve",
       "design.md §3 equivalence: CG == CHOLMOD (the augmented method's initial solve)",
       "||u_cg - u_cholmod|| / ||u_cholmod|| in its band, both converged",
       {"relative"},
       detail::measure_cg_vs_cholmod},
      {"solver_equivalence_cylinder",
       "Nonlinear CG and dynamic relaxation reach the Newton minimizer (speed/accuracy)",
       "thesis §4.2-4.5: nonlinear CG and dynamic relaxation (SS22) on the cylinder under "
       "gravity, neo-Hookean, Table 4.1 parameters; reference by truncated Newton",
       "||u - u_newton|| / ||u_newton|| of each method in its band, all converged",
       {"relative", "residual"},
       detail::measure_solver_trade},
      {"augmented_cut_vs_cut_first",
       "Interactive cut with the augmented solver equals cutting first and solving",
       "Yeung, Crouch & Pothen 2016 §3 (augmented updates) on thesis §3.2 cuts; "
       "reference_data/scenes/cube_cut_augmented.json",
       "||u_augmented - u_cg|| / ||u_cg|| in its band; same cut mesh, every step solved with the "
       "initial factor (no refactorization), both converged",
       {"relative"},
       detail::measure_augmented_cut},
      {"performance_table_4_5",
       "Cost per iteration vs thesis Table 4.5 (machine baseline)",
       "thesis §4.5.2, Table 4.5 (MFLOP/iteration, iterations/s, % of the vector-add baseline)",
       "every row: counted MFLOP per iteration over the thesis' in its band; MFLOP/s as a "
       "fraction of the vector-add baseline, both in thread CPU time measured interleaved in "
       "the same run, in its band; every run completes its iterations",
       {"mflop_per_iteration_ratio", "fraction_of_baseline"},
       detail::measure_table_4_5},
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
  sum.environment = capture_environment();
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
    r.criterion = c.criterion;
    try {
      // The bands first: a check with a missing or malformed band fails without running.
      for (const std::string& b : c.bands) (void)ctx.band(c.id, b);
      Measurement m = c.measure(ctx);
      bool all_in = !m.comparisons.empty();
      for (Comparison& cmp : m.comparisons) {
        JudgedComparison j;
        j.quantity = std::move(cmp.quantity);
        j.band = cmp.band;
        j.value = cmp.value;
        j.bounds = Band{kNaN, kNaN};
        try {
          j.bounds = ctx.band(c.id, cmp.band);
          j.passed = j.bounds.contains(j.value);
          j.margin = band_margin(j.value, j.bounds);
        } catch (const Error& e) {
          m.detail += std::string(" ") + e.what() + ".";
        }
        all_in = all_in && j.passed;
        r.comparisons.push_back(std::move(j));
      }
      if (m.comparisons.empty()) m.detail += " The measurement returned no comparison.";
      r.passed = m.conditions_ok && all_in;
      r.detail = std::move(m.detail);
      r.tables = std::move(m.tables);
      r.plots = std::move(m.plots);
    } catch (const std::exception& e) {
      r.passed = false;
      r.detail = std::string("exception: ") + e.what();
    }
    for (const std::string& b : c.bands) r.justifications.emplace_back(b, ctx.why(c.id, b));
    for (const JudgedComparison& j : r.comparisons) {
      bool listed = false;
      for (const auto& w : r.justifications) listed = listed || w.first == j.band;
      if (!listed) r.justifications.emplace_back(j.band, ctx.why(c.id, j.band));
    }
    r.seconds = t.seconds();
    (r.passed ? sum.passed : sum.failed)++;
    sum.results.push_back(std::move(r));
  }
  sum.seconds = total.seconds();
  return sum;
}

}  // namespace incise::certify
