/// Per-iteration cost of the relaxation algorithms (thesis §4.5.2, Table 4.5 analogue): linear
/// CG step (linear model), nonlinear CG step with the Newton and the secant line search
/// (Polak-Ribière, ε_newton = 0.1) and SS22 dynamic step, for every registered material on both
/// thesis-like cylinder meshes (§4.2: length 0.1 m, radius 0.03 m, E = 1e4 Pa, ν = 0.3,
/// ρ = 1000 kg/m³, g = 9.8 m/s², γ = 8, one end fixed; make_thesis_cylinder_small() 1296 tets,
/// make_thesis_cylinder_large() 9450 tets). Every run starts from u = 0, like the thesis' "first
/// 1.0 seconds that experiments ran". Counters: iter/s, MFLOP/iter and MFLOP/s from the counted
/// flops (Problem::flops plus solver vector operations), and %baseline = MFLOP/s as a percentage
/// of the vector-add baseline (Table 4.5's "% peak": repeated a ← a + b on 1024 doubles)
/// measured in this process (incise::bench::vector_add_mflops()).
///
/// Extra flag: --table45_csv=<path> writes the Table 4.5 analogue (one row per benchmark, with
/// the thesis' values beside ours) as CSV and prints it as a Markdown table. Columns:
/// material,mesh,relaxation,line_search,elements,pct_baseline,iter_per_s,mflop_per_iter,
/// mflop_per_s,baseline_mflops,thesis_pct_peak,thesis_iter_per_s,thesis_mflop_per_iter
/// (thesis columns empty where Table 4.5 has no row; its peak was 246 MFLOP/s on a PIII/1GHz).
#include <incise/fem/elastic_problem.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/solver/dynamic_relaxation.hpp>
#include <incise/solver/linear_cg.hpp>
#include <incise/solver/nonlinear_cg.hpp>
#include <incise_bench/context.hpp>

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace {

using namespace incise;

std::unique_ptr<fem::ElasticProblem> cylinder(const std::string& material, bool large) {
  const mesh::MeshData m =
      large ? mesh::make_thesis_cylinder_large() : mesh::make_thesis_cylinder_small();
  material::Parameters p;  // Table 4.1
  p.youngs_modulus = 1e4;
  p.poisson_ratio = 0.3;
  p.density = 1000.0;
  p.gamma = material == "veronda-westmann" ? 8.0 : 0.0;
  auto prob = std::make_unique<fem::ElasticProblem>(m, material::Material(material, p));
  prob->fix_nodes(fem::nodes_on_plane(m, 0, 0.0));
  prob->add_gravity(Vec3(0.0, 0.0, -9.8));
  return prob;
}

void set_counters(benchmark::State& state, double iterations, double flops, Index elements) {
  state.counters["iter/s"] = benchmark::Counter(iterations, benchmark::Counter::kIsRate);
  state.counters["MFLOP/iter"] = flops / iterations * 1e-6;
  state.counters["MFLOP/s"] = benchmark::Counter(flops * 1e-6, benchmark::Counter::kIsRate);
  // % of the vector-add baseline (Table 4.5's "% peak"), as a rate over the same time.
  state.counters["%baseline"] = benchmark::Counter(
      flops * 1e-6 * 100.0 / bench::vector_add_mflops(), benchmark::Counter::kIsRate);
  state.counters["elements"] = double(elements);
}

// What one registered benchmark measures (for the Table 4.5 CSV).
struct Meta {
  std::string material, mesh, relaxation, line_search;
};
std::map<std::string, Meta>& registry() {
  static std::map<std::string, Meta> r;
  return r;
}

void BM_LinearCgStep(benchmark::State& state, const std::string& material, bool large) {
  auto p = cylinder(material, large);
  double iters = 0, flops = 0;
  for (auto _ : state) {
    VecX u = VecX::Zero(p->size());
    solver::LinearCgOptions o;
    o.stop.epsilon = 0.0;  // run the full budget
    o.budget.max_iterations = 50;
    o.recompute_residual = false;
    const solver::SolverReport rep = solver::linear_cg(*p, u, o);
    iters += double(rep.iterations);
    flops += double(rep.flops);
    benchmark::DoNotOptimize(u.data());
  }
  set_counters(state, iters, flops, p->num_elements());
}

void BM_NonlinearCgStep(benchmark::State& state, const std::string& material, bool large,
                        solver::LineSearchKind line_search) {
  auto p = cylinder(material, large);
  double iters = 0, flops = 0;
  for (auto _ : state) {
    VecX u = VecX::Zero(p->size());
    solver::NonlinearCgOptions o;
    o.stop.epsilon = 0.0;
    o.budget.max_iterations = 20;
    o.line_search = line_search;
    o.epsilon_newton = 0.1;  // §4.5.1
    const solver::SolverReport rep = solver::nonlinear_cg(*p, u, o);
    iters += double(rep.iterations);
    flops += double(rep.flops);
    benchmark::DoNotOptimize(u.data());
  }
  set_counters(state, iters, flops, p->num_elements());
}

void BM_DynamicStep(benchmark::State& state, const std::string& material, bool large) {
  auto p = cylinder(material, large);
  double iters = 0, flops = 0;
  for (auto _ : state) {
    VecX u = VecX::Zero(p->size());
    solver::DynamicRelaxationOptions o;
    o.time_step = 1e-4;  // well below the critical step of both meshes: the run stays bounded
    o.damping = 20.0;
    o.stop.epsilon = 0.0;
    o.budget.max_iterations = 100;
    const solver::SolverReport rep = solver::dynamic_relaxation(*p, u, o);
    iters += double(rep.iterations);
    flops += double(rep.flops);
    benchmark::DoNotOptimize(u.data());
  }
  set_counters(state, iters, flops, p->num_elements());
}

// Every registered material is enrolled automatically, on both meshes.
const bool kRegistered = [] {
  auto add = [](const std::string& name, const Meta& meta, auto fn) {
    registry()[name] = meta;
    benchmark::RegisterBenchmark(name.c_str(), fn)->Unit(benchmark::kMillisecond);
  };
  for (const bool large : {false, true}) {
    const std::string mesh = large ? "large" : "small";
    add("BM_LinearCgStep/linear/" + mesh, Meta{"linear", mesh, "static", "linear CG"},
        [large](benchmark::State& s) { BM_LinearCgStep(s, "linear", large); });
    for (const std::string& m : material::registered_material_names()) {
      if (m != "linear") {
        add("BM_NonlinearCgStep/" + m + "/newton/" + mesh, Meta{m, mesh, "static", "Newton"},
            [m, large](benchmark::State& s) {
              BM_NonlinearCgStep(s, m, large, solver::LineSearchKind::kNewton);
            });
        add("BM_NonlinearCgStep/" + m + "/secant/" + mesh, Meta{m, mesh, "static", "Secant"},
            [m, large](benchmark::State& s) {
              BM_NonlinearCgStep(s, m, large, solver::LineSearchKind::kSecant);
            });
      }
      add("BM_DynamicStep/" + m + "/" + mesh, Meta{m, mesh, "dynamic", ""},
          [m, large](benchmark::State& s) { BM_DynamicStep(s, m, large); });
    }
  }
  return true;
}();

// Thesis Table 4.5 (PIII/1GHz, 1230/9300-element Delaunay meshes): reference values.
struct Thesis {
  const char *material, *mesh, *relaxation, *line_search;
  double pct_peak, iter_per_s, mflop_per_iter;
};
constexpr Thesis kTable45[] = {{"linear", "small", "dynamic", "", 49, 628, 0.2},
                               {"linear", "small", "static", "linear CG", 56, 708, 0.2},
                               {"stvk", "small", "static", "Newton", 48, 71, 1.7},
                               {"stvk", "small", "static", "Secant", 53, 113, 1.2},
                               {"stvk", "small", "dynamic", "", 62, 426, 0.4},
                               {"neohookean", "small", "static", "Newton", 85, 109, 1.9},
                               {"neohookean", "small", "static", "Secant", 77, 144, 1.3},
                               {"neohookean", "small", "dynamic", "", 54, 356, 0.4},
                               {"veronda-westmann", "small", "static", "Newton", 90, 91, 2.4},
                               {"veronda-westmann", "small", "static", "Secant", 80, 120, 1.7},
                               {"veronda-westmann", "small", "dynamic", "", 61, 327, 0.5},
                               {"neohookean", "large", "static", "Newton", 73, 12, 14.2},
                               {"neohookean", "large", "static", "Secant", 66, 16, 9.9},
                               {"neohookean", "large", "dynamic", "", 49, 41, 2.9}};

// Console output as usual, plus the per-run counters kept for the Table 4.5 CSV (the median of
// repetitions when --benchmark_repetitions > 1, else the single run).
class Table45Reporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs) {
      const std::string name = r.run_name.function_name;
      const bool median = r.run_type == Run::RT_Aggregate && r.aggregate_name == "median";
      if (r.run_type == Run::RT_Iteration && !rows_.count(name)) rows_[name] = r.counters;
      if (median) rows_[name] = r.counters;
    }
    ConsoleReporter::ReportRuns(runs);
  }
  std::map<std::string, benchmark::UserCounters> rows_;
};

void write_table45(const std::string& path, const Table45Reporter& rep) {
  std::ofstream csv(path);
  csv << "material,mesh,relaxation,line_search,elements,pct_baseline,iter_per_s,mflop_per_iter,"
         "mflop_per_s,baseline_mflops,thesis_pct_peak,thesis_iter_per_s,thesis_mflop_per_iter\n";
  std::printf(
      "\n| material | mesh | relaxation | line search | %% baseline (thesis %% peak) | "
      "iter/s (thesis) | MFLOP/iter (thesis) |\n|---|---|---|---|---|---|---|\n");
  const double baseline = bench::vector_add_mflops();
  // Rows in the thesis' order: material (linear, StVK, neo-Hookean, VW, others), mesh, then
  // static Newton / linear CG, static secant, dynamic.
  auto rank = [](const Meta& m) {
    const char* order[] = {"linear", "stvk", "neohookean", "veronda-westmann"};
    int mat = 4;
    for (int i = 0; i < 4; ++i)
      if (m.material == order[i]) mat = i;
    const int method = m.relaxation == "dynamic" ? 2 : m.line_search == "Secant" ? 1 : 0;
    return std::make_tuple(mat, m.material, m.mesh == "large", method);
  };
  std::vector<std::pair<std::string, Meta>> rows(registry().begin(), registry().end());
  std::sort(rows.begin(), rows.end(),
            [&](const auto& a, const auto& b) { return rank(a.second) < rank(b.second); });
  for (const auto& [name, meta] : rows) {
    const auto it = rep.rows_.find(name);
    if (it == rep.rows_.end()) continue;  // filtered out
    auto counter = [&](const char* c) {
      const auto f = it->second.find(c);
      return f == it->second.end() ? 0.0 : double(f->second.value);
    };
    const Thesis* t = nullptr;
    for (const Thesis& row : kTable45)
      if (meta.material == row.material && meta.mesh == row.mesh &&
          meta.relaxation == row.relaxation && meta.line_search == row.line_search)
        t = &row;
    char thesis[96] = ",,";
    if (t)
      std::snprintf(thesis, sizeof thesis, "%g,%g,%g", t->pct_peak, t->iter_per_s,
                    t->mflop_per_iter);
    csv << meta.material << ',' << meta.mesh << ',' << meta.relaxation << ',' << meta.line_search
        << ',' << counter("elements") << ',' << counter("%baseline") << ',' << counter("iter/s")
        << ',' << counter("MFLOP/iter") << ',' << counter("MFLOP/s") << ',' << baseline << ','
        << thesis << '\n';
    auto ref = [&](double v) {
      char b[32];
      std::snprintf(b, sizeof b, t ? " (%g)" : "", v);
      return std::string(b);
    };
    std::printf("| %s | %s | %s | %s | %.0f%s | %.0f%s | %.3f%s |\n", meta.material.c_str(),
                meta.mesh.c_str(), meta.relaxation.c_str(), meta.line_search.c_str(),
                counter("%baseline"), ref(t ? t->pct_peak : 0).c_str(), counter("iter/s"),
                ref(t ? t->iter_per_s : 0).c_str(), counter("MFLOP/iter"),
                ref(t ? t->mflop_per_iter : 0).c_str());
  }
  std::printf("\nvector-add baseline %.0f MFLOP/s (thesis: 246 MFLOP/s); CSV: %s\n", baseline,
              path.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  std::string table45;
  std::vector<char*> args;
  for (int i = 0; i < argc; ++i) {
    const char* kFlag = "--table45_csv=";
    if (std::strncmp(argv[i], kFlag, std::strlen(kFlag)) == 0)
      table45 = argv[i] + std::strlen(kFlag);
    else
      args.push_back(argv[i]);
  }
  int n = int(args.size());
  benchmark::Initialize(&n, args.data());
  if (benchmark::ReportUnrecognizedArguments(n, args.data())) return 1;
  incise::bench::add_context();
  Table45Reporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  if (!table45.empty()) write_table45(table45, reporter);
  benchmark::Shutdown();
  return 0;
}
