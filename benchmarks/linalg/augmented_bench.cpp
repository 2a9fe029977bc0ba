/// \file augmented_bench.cpp
/// Augmented-matrix updates (Yeung, Crouch & Pothen 2016) on the paper's beams (5×5×h nodes),
/// bricks and the liver.
///
/// Two modes:
///  - Google Benchmark (default): BM_AugmentedDeformStep/h — mean deformation update over a
///    16-step run on beams of h = 16 … 1024 nodes; BM_Factor{Supernodal,Simplicial}/h — analyze +
///    factorize + solve, the measurement behind the supernodal-vs-simplicial choice
///    (docs/augmented.md); BM_Step3FullBackward/1024 — step 3 of §3.2 alone (restricted forward +
///    full backward substitution, METIS LDLᵀ); BM_CholmodNumericRefactor/1024 and
///    BM_CholmodSolve/1024 — the parts of the refactorization route (CHOLMOD's ordering).
///  - Per-step table (the paper's Fig. 5/7 experiments):
///      augmented_bench --table deform|cut [--h 1024 | --brick N | --mesh FILE|liver]
///                      [--steps 32] [--pcg-every 8] [--pcg-seconds 20]
///                      [--precond none|diag|spai] [--supernodal] [--refactor]
///                      [--default-ordering|--amd] (K⁰ ordering; METIS by default)
///                      [--ref-kind simplicial|supernodal] (reference refactorization)
///                      [--schur gmres|direct] (eq. 17: GMRES, or GMRES preconditioned by the
///                      explicit H R⁻¹ J in capacitance form; then "+N Schur solves" counts the
///                      restricted solves spent on new columns of G)
///                      [--threads T] (threads of both sides: step 3's backward pass, and the
///                      OpenBLAS threads of a supernodal reference refactorization — CHOLMOD's
///                      simplicial factorization is serial, so with --ref-kind simplicial the
///                      reference has one thread whatever T; 1 by default)
///                      [--gmres-tol TOL] (relative residual of eq. 17; 1e-12 by default)
///                      [--csv FILE] (also write the rows as CSV, for yeung2016_plots)
///    prints the thread counts of both sides and the load average before and after, then one
///    Markdown row per step: m, GMRES iterations, closure sizes, update wall and CPU time and
///    rate, the reference refactorization + solve (analysis + factorization + solve) in wall and
///    CPU time, for deformation also the numeric-only refactorization + solve with the pattern
///    kept (symbolic analysis of K⁰ reused), the speed-ups over both in wall and CPU time,
///    Jacobi-PCG time, relative and backward error; and a summary line of the speed-ups over
///    the steps ≥ 1 with m ≤ 100 (min / median / max). CPU time is the process's (all threads).
///    `--mesh liver` is reference_data/meshes/liver_coarse.mesh (mm, scaled to m).

#include "yeung2016_experiment.hpp"

#include <incise/core/environment.hpp>
#include <incise/linalg/ldl_closure_solver.hpp>

#include <incise_bench/context.hpp>

#include <benchmark/benchmark.h>

#include <dlfcn.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

namespace {

using incise::yeung2016::Info;
using incise::yeung2016::Kind;
using incise::yeung2016::Options;
using incise::yeung2016::Row;

void BM_AugmentedDeformStep(benchmark::State& state) {
  const int h = static_cast<int>(state.range(0));
  // Build once: beam, factor, 16 constraints (m = 48); time one more constraint + solve.
  incise::material::Parameters par;
  const incise::material::Material mat("linear", par);
  Options opt;
  opt.h = h;
  opt.steps = 16;
  opt.exact = false;
  Info info;
  double total = 0;
  int count = 0;
  for (auto _ : state) {
    state.PauseTiming();
    const std::vector<Row> rows = incise::yeung2016::run(opt, info);
    state.ResumeTiming();
    // The run itself is the measured object; report the mean update time of its steps ≥ 1.
    for (size_t i = 1; i < rows.size(); ++i) {
      total += rows[i].t_changes + rows[i].t_solve;
      ++count;
    }
  }
  state.counters["update_s"] = count > 0 ? total / count : 0;
  state.counters["update_Hz"] = count > 0 && total > 0 ? count / total : 0;
  state.counters["nodes"] = info.nodes;
  state.counters["nnz_L"] = static_cast<double>(info.nnz_l);
}
BENCHMARK(BM_AugmentedDeformStep)
    ->Arg(16)
    ->Arg(64)
    ->Arg(256)
    ->Arg(1024)
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

void factor_bench(benchmark::State& state, incise::linalg::CholmodKind kind) {
  const int h = static_cast<int>(state.range(0));
  Options opt;
  opt.h = h;
  incise::material::Parameters par;
  const incise::material::Material mat("linear", par);
  const incise::mesh::MeshData mesh = incise::mesh::make_beam(h, opt.spacing);
  // Anchored at z = 0 (the bottom face of make_beam).
  const auto beam = incise::yeung2016::detail::anchored_beam(mesh, mat.lame(), 1e-12);
  const incise::linalg::SparseMatrix k = beam.assemble();
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(k.rows());
  incise::linalg::CholmodOptions co;
  co.kind = kind;
  std::uint64_t version = 1;
  for (auto _ : state) {
    incise::linalg::CholmodFactor f(co);
    if (f.compute(k, version++) != incise::linalg::FactorStatus::kOk) {
      state.SkipWithError("factorization failed");
      break;
    }
    Eigen::VectorXd x;
    (void)f.solve(b, x);
    benchmark::DoNotOptimize(x.data());
    state.counters["nnz_L"] = static_cast<double>(f.nnz_l());
    state.counters["MFlop_factor"] = f.factor_flops() / 1e6;
  }
}
void BM_FactorSupernodal(benchmark::State& s) {
  factor_bench(s, incise::linalg::CholmodKind::kSupernodal);
}
void BM_FactorSimplicial(benchmark::State& s) {
  factor_bench(s, incise::linalg::CholmodKind::kSimplicialLdl);
}
BENCHMARK(BM_FactorSupernodal)->Arg(64)->Arg(256)->Arg(1024)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FactorSimplicial)->Arg(64)->Arg(256)->Arg(1024)->Unit(benchmark::kMillisecond);

// Step 3 of §3.2 in isolation: one restricted forward + full backward substitution
// (ClosureLdlSolver::solve_sparse_rhs) with the METIS LDLᵀ factor of the beam, beside one full
// CHOLMOD solve with the factor of CHOLMOD's own ordering (the solve inside the refactorization
// route) and CHOLMOD's numerical refactorization alone. Counters: |L|, bytes of L read.
void BM_Step3FullBackward(benchmark::State& state) {
  const int h = static_cast<int>(state.range(0));
  incise::material::Parameters par;
  const incise::material::Material mat("linear", par);
  const incise::mesh::MeshData mesh = incise::mesh::make_beam(h, 0.01);
  // Anchored at z = 0 (the bottom face of make_beam).
  const auto beam = incise::yeung2016::detail::anchored_beam(mesh, mat.lame(), 1e-12);
  const incise::linalg::SparseMatrix k = beam.assemble();
  incise::linalg::CholmodFactor f(
      {incise::linalg::CholmodKind::kSimplicialLdl, incise::linalg::CholmodOrdering::kMetis});
  if (f.compute(k, 1) != incise::linalg::FactorStatus::kOk) {
    state.SkipWithError("factorization failed");
    return;
  }
  incise::linalg::ClosureLdlSolver solver(f.extract_ldl(), static_cast<int>(state.range(1)));
  const std::vector<int> b_idx{beam.num_dofs - 2};
  const std::vector<double> b_val{1.0};
  const std::vector<int> fwd = solver.closure(b_idx);
  Eigen::VectorXd x;
  for (auto _ : state) {
    solver.solve_sparse_rhs(b_idx, b_val, fwd, x);
    benchmark::DoNotOptimize(x.data());
  }
  state.counters["nnz_L"] = static_cast<double>(solver.factor().nnz_l());
  state.counters["supernodes"] = solver.num_supernodes();
  state.counters["MB_L_values"] = 8e-6 * static_cast<double>(solver.factor().values.size());
  state.counters["threads"] = solver.backward_threads();
  state.counters["serial_frac"] = solver.backward_serial_fraction();
  state.counters["max_bin_frac"] = solver.backward_max_bin_fraction();
}
// Args: beam length h, threads of the backward pass. With 2 threads the CPU column sums both
// threads' time (Google Benchmark measures the process), so compare the real-time column.
BENCHMARK(BM_Step3FullBackward)
    ->Args({1024, 1})
    ->Args({1024, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void refactor_parts(benchmark::State& state, int part) {
  const int h = static_cast<int>(state.range(0));
  incise::material::Parameters par;
  const incise::material::Material mat("linear", par);
  const incise::mesh::MeshData mesh = incise::mesh::make_beam(h, 0.01);
  // Anchored at z = 0 (the bottom face of make_beam).
  const auto beam = incise::yeung2016::detail::anchored_beam(mesh, mat.lame(), 1e-12);
  const incise::linalg::SparseMatrix k = beam.assemble();
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(k.rows());
  incise::linalg::CholmodFactor f(
      {incise::linalg::CholmodKind::kSimplicialLdl, incise::linalg::CholmodOrdering::kDefault});
  if (f.compute(k, 1) != incise::linalg::FactorStatus::kOk) {
    state.SkipWithError("factorization failed");
    return;
  }
  Eigen::VectorXd x;
  for (auto _ : state) {
    if (part == 0) {
      (void)f.factorize(k);  // numerical refactorization, analysis cached
    } else {
      (void)f.solve(b, x);
      benchmark::DoNotOptimize(x.data());
    }
  }
  state.counters["nnz_L"] = static_cast<double>(f.nnz_l());
}
void BM_CholmodNumericRefactor(benchmark::State& s) {
  refactor_parts(s, 0);
}
void BM_CholmodSolve(benchmark::State& s) {
  refactor_parts(s, 1);
}
BENCHMARK(BM_CholmodNumericRefactor)->Arg(1024)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CholmodSolve)->Arg(1024)->Unit(benchmark::kMillisecond);

// OpenBLAS's thread count (CHOLMOD's supernodal factorization runs its dense kernels through
// BLAS). Looked up at run time so that the benchmark still links against another BLAS; returns
// false when the loaded BLAS has no such control.
bool set_blas_threads(int threads) {
  using SetThreads = void (*)(int);
  const auto set =
      reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));  // NOLINT
  if (set == nullptr) return false;
  set(threads);
  return true;
}

std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string one, five, fifteen;
  in >> one >> five >> fifteen;
  return one + " " + five + " " + fifteen;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n == 0 ? 0.0 : n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// "min / median / max" of `v` (or "-" when empty).
std::string spread(const std::vector<double>& v) {
  if (v.empty()) return "-";
  char b[96];
  std::snprintf(b, sizeof b, "%.1f / %.1f / %.1f", *std::min_element(v.begin(), v.end()), median(v),
                *std::max_element(v.begin(), v.end()));
  return b;
}

int run_table(int argc, char** argv) {
  Options opt;
  std::string csv_path;
  opt.h = 1024;
  opt.steps = 32;
  opt.kind = std::strcmp(argv[2], "cut") == 0 ? Kind::kCut : Kind::kDeform;
  for (int i = 3; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() { return i + 1 < argc ? std::string(argv[++i]) : std::string(); };
    if (a == "--h") {
      opt.h = std::stoi(next());
    } else if (a == "--brick") {
      opt.geometry = incise::yeung2016::Geometry::kBrick;
      opt.brick_n = std::stoi(next());
    } else if (a == "--mesh") {
      opt.geometry = incise::yeung2016::Geometry::kFile;
      opt.mesh_file = next();
      if (opt.mesh_file == "liver")
        opt.mesh_file = std::string(INCISE_SOURCE_DIR) + "/reference_data/meshes/liver_coarse.mesh";
    } else if (a == "--schur") {
      opt.schur_solver = next() == "direct" ? incise::linalg::SchurSolver::kDirectCached
                                            : incise::linalg::SchurSolver::kGmres;
    } else if (a == "--ref-kind") {
      opt.reference_kind = next() == "supernodal" ? incise::linalg::CholmodKind::kSupernodal
                                                  : incise::linalg::CholmodKind::kSimplicialLdl;
    } else if (a == "--csv") {
      csv_path = next();
    } else if (a == "--steps") {
      opt.steps = std::stoi(next());
    } else if (a == "--pcg-every") {
      opt.pcg_every = std::stoi(next());
    } else if (a == "--pcg-seconds") {
      opt.pcg_seconds = std::stod(next());
    } else if (a == "--precond") {
      const std::string p = next();
      opt.preconditioner = p == "none"   ? incise::linalg::SchurPreconditioner::kNone
                           : p == "spai" ? incise::linalg::SchurPreconditioner::kTridiagonalSpai
                                         : incise::linalg::SchurPreconditioner::kDiagonal;
    } else if (a == "--metis") {
      opt.ordering = incise::linalg::CholmodOrdering::kMetis;
    } else if (a == "--default-ordering") {
      opt.ordering = incise::linalg::CholmodOrdering::kDefault;
    } else if (a == "--amd") {
      opt.ordering = incise::linalg::CholmodOrdering::kAmd;
    } else if (a == "--supernodal") {
      opt.cholmod = incise::linalg::CholmodKind::kSupernodal;
    } else if (a == "--refactor") {
      opt.background_refactor = true;
    } else if (a == "--no-exact") {
      opt.exact = false;
    } else if (a == "--threads") {
      opt.solve_threads = std::stoi(next());
    } else if (a == "--gmres-tol") {
      opt.gmres_tolerance = std::stod(next());
    } else {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return 2;
    }
  }
  const bool blas_set = set_blas_threads(opt.solve_threads);
  const bool simplicial_ref = opt.reference_kind == incise::linalg::CholmodKind::kSimplicialLdl;
  const std::string load_before = load_average();
  Info info;
  const std::vector<Row> rows = incise::yeung2016::run(opt, info);
  std::printf(
      "# %s: %d nodes, %d tetrahedra, n0 = %d DOFs, nnz(K) = %lld, |L| = %lld, s = %.4g m\n",
      info.name.c_str(), info.nodes, info.elements, info.n0, info.nnz_k, info.nnz_l, info.spacing);
  std::printf("# assembly %.3f s, initial factorization + LDL' extraction %.3f s; blas: %s\n",
              info.t_assemble, info.t_initial_factor, incise::loaded_blas().c_str());
  std::printf(
      "# threads: update %d (step 3); reference refactorization %s%s\n", opt.solve_threads,
      simplicial_ref
          ? "simplicial LDL', serial: 1 thread"
          : ("supernodal, " + std::to_string(opt.solve_threads) + " BLAS threads").c_str(),
      blas_set || simplicial_ref ? "" : " (BLAS thread count not settable: OPENBLAS_NUM_THREADS)");
  std::printf("# load average (1/5/15 min) before %s, after %s\n", load_before.c_str(),
              load_average().c_str());
  std::printf(
      "| step | n | m | GMRES it | clos f | clos y | clos Ja2 | clos step3 | changes ms | solve "
      "ms (setup/1/2/3) | update Hz | update ms wall / CPU | refactor+solve ms wall / CPU | "
      "numeric refactor+solve ms wall / CPU | speed-up ref wall / CPU | speed-up num wall / CPU "
      "| PCG ms wall / CPU (it) | rel. error | backward error | status |\n");
  std::printf(
      "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  std::vector<double> ref_wall, ref_cpu, num_wall, num_cpu;  // speed-ups, steps ≥ 1, m ≤ 100
  for (const Row& r : rows) {
    const double upd = r.t_changes + r.t_solve;
    const double ref = r.t_refactor + r.t_refactor_solve;
    char pcg[64] = "-";
    if (r.t_pcg >= 0)
      std::snprintf(pcg, sizeof pcg, "%.1f / %.1f (%ld%s)", 1e3 * r.t_pcg, 1e3 * r.cpu_pcg,
                    r.pcg_iterations, r.pcg_converged ? "" : ", not conv.");
    char its[48];
    if (opt.schur_solver == incise::linalg::SchurSolver::kDirectCached)
      std::snprintf(its, sizeof its, "%d (+%d Schur solves)", r.gmres_iterations, r.schur_solves);
    else
      std::snprintf(its, sizeof its, "%d", r.gmres_iterations);
    char ref_txt[48] = "-", ref_speed[48] = "-", num[48] = "-", num_speed[48] = "-";
    const bool have_ref = opt.exact && ref > 0 && upd > 0 && r.cpu_update > 0;
    if (have_ref) {
      std::snprintf(ref_txt, sizeof ref_txt, "%.1f / %.1f", 1e3 * ref, 1e3 * r.cpu_refactor);
      std::snprintf(ref_speed, sizeof ref_speed, "%.1f / %.1f", ref / upd,
                    r.cpu_refactor / r.cpu_update);
    }
    const bool have_num = r.cpu_numeric_refactor >= 0 && upd > 0 && r.cpu_update > 0;
    if (have_num) {
      std::snprintf(num, sizeof num, "%.1f / %.1f", 1e3 * r.t_numeric_refactor,
                    1e3 * r.cpu_numeric_refactor);
      std::snprintf(num_speed, sizeof num_speed, "%.1f / %.1f", r.t_numeric_refactor / upd,
                    r.cpu_numeric_refactor / r.cpu_update);
    }
    if (r.step >= 1 && r.m <= 100) {
      if (have_ref) {
        ref_wall.push_back(ref / upd);
        ref_cpu.push_back(r.cpu_refactor / r.cpu_update);
      }
      if (have_num) {
        num_wall.push_back(r.t_numeric_refactor / upd);
        num_cpu.push_back(r.cpu_numeric_refactor / r.cpu_update);
      }
    }
    std::printf(
        "| %d | %d | %d | %s | %d | %d | %d | %d | %.3f | %.2f (%.2f/%.2f/%.2f/%.2f) | %.0f | "
        "%.2f / %.2f | %s | %s | %s | %s | %s | %.1e | %.1e | %s%s |\n",
        r.step, r.n, r.m, its, r.closure_f, r.closure_y, r.closure_ja2, r.closure_step3,
        1e3 * r.t_changes, 1e3 * r.t_solve, 1e3 * r.t_setup, 1e3 * r.t_step1, 1e3 * r.t_step2,
        1e3 * r.t_step3, upd > 0 ? 1.0 / upd : 0.0, 1e3 * upd, 1e3 * r.cpu_update, ref_txt, num,
        ref_speed, num_speed, pcg, r.rel_error, r.rel_residual, r.status.c_str(),
        r.swapped ? " (swap)" : "");
  }
  std::printf(
      "# speed-up over steps >= 1 with m <= 100 (%zu steps), min / median / max: refactorization "
      "+ solve wall %s, CPU %s; numeric refactorization + solve (pattern kept) wall %s, CPU %s\n",
      ref_cpu.size(), spread(ref_wall).c_str(), spread(ref_cpu).c_str(), spread(num_wall).c_str(),
      spread(num_cpu).c_str());
  if (!csv_path.empty()) {
    FILE* out = std::fopen(csv_path.c_str(), "w");
    if (out == nullptr) {
      std::fprintf(stderr, "cannot write %s\n", csv_path.c_str());
      return 1;
    }
    std::fprintf(
        out, "# %s,%s,%d,%d,%d,%lld,threads=%d,schur=%s,precond=%s,ref=%s\n", info.name.c_str(),
        opt.kind == Kind::kCut ? "cut" : "deform", info.nodes, info.elements, info.n0, info.nnz_l,
        opt.solve_threads,
        opt.schur_solver == incise::linalg::SchurSolver::kDirectCached ? "direct" : "gmres",
        opt.preconditioner == incise::linalg::SchurPreconditioner::kNone       ? "none"
        : opt.preconditioner == incise::linalg::SchurPreconditioner::kDiagonal ? "diag"
                                                                               : "spai",
        simplicial_ref ? "simplicial" : "supernodal");
    std::fprintf(
        out,
        "step,n,m,gmres_it,closure_f,closure_y,closure_ja2,closure_step3,t_update,"
        "t_setup,t_step1,t_step2,t_step3,t_refactor,cpu_update,cpu_refactor,"
        "cpu_numeric_refactor,t_pcg,cpu_pcg,pcg_it,pcg_converged,rel_error,backward_error,ok,"
        "t_numeric_refactor\n");
    for (const Row& r : rows)
      std::fprintf(out,
                   "%d,%d,%d,%d,%d,%d,%d,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,"
                   "%.6g,%ld,%d,%.6g,%.6g,%d,%.6g\n",
                   r.step, r.n, r.m, r.gmres_iterations, r.closure_f, r.closure_y, r.closure_ja2,
                   r.closure_step3, r.t_changes + r.t_solve, r.t_setup, r.t_step1, r.t_step2,
                   r.t_step3, r.t_refactor + r.t_refactor_solve, r.cpu_update, r.cpu_refactor,
                   r.cpu_numeric_refactor, r.t_pcg, r.cpu_pcg, r.pcg_iterations,
                   r.pcg_converged ? 1 : 0, r.rel_error, r.rel_residual, r.status == "ok" ? 1 : 0,
                   r.t_numeric_refactor);
    std::fclose(out);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 3 && std::strcmp(argv[1], "--table") == 0) return run_table(argc, argv);
  ::benchmark::Initialize(&argc, argv);
  if (::benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  ::incise::bench::add_context();
  ::benchmark::RunSpecifiedBenchmarks();
  ::benchmark::Shutdown();
  return 0;
}
