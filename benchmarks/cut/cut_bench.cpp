/// Time per sweep-triangle step (thesis §3.2) on ~10k- and ~100k-tetrahedron boxes with the
/// *same element size* h, so that every step meets the same number of elements: the cost of a
/// step must depend on the cut, not on the mesh (target: 100k/10k time ratio ≤ 1.5).
///
/// A vertical blade entering through the top face, 2.63h deep, moves along a serpentine path in the
/// middle of the box, h/2 per move, two sweep triangles per move; each benchmark iteration is one
/// sweep triangle (selection, snapping, dissection, degeneracy removal). The search grid is built
/// before the timed loop (it is rebuilt only when deformed positions change in bulk, i.e. once per
/// solver update). Arg 1 = 1 adds the O(n) free-component check after every dissecting step, to
/// show its cost separately (the interactive loop can run it less often).
#include <benchmark/benchmark.h>
#include <incise/cut/cutter.hpp>
#include <incise/fem/elastic_problem.hpp>
#include <incise/interactive/augmented_cut_session.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/solver/linear_cg.hpp>
#include <incise_bench/context.hpp>

namespace {

using incise::Index;
using incise::Vec3;

constexpr double kH = 1.0 / 12.0;  // element (cube) size, m
constexpr int kTriangles = 200;    // sweep triangles per run (fits in the 10k box)

void BM_CutStep(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const bool components = state.range(1) != 0;
  const double side = n * kH;
  incise::cut::CutMesh mesh(incise::mesh::make_box(n, n, n, side, side, side));
  incise::cut::CutOptions opt;
  opt.check_components = components;
  opt.free_components = incise::cut::FreeComponentPolicy::kReport;
  incise::cut::Cutter cutter(mesh, opt);
  // Warm-up step far away builds the search grid.
  (void)cutter.step(Vec3(10, 10, 10), Vec3(11, 10, 10), Vec3(10, 11, 10));
  const Vec3 centre = Vec3::Constant(side / 2);
  // The blade reaches from above the top face to 2.63 h below it (a scalpel enters from the
  // surface; the search starts from boundary hits and incomplete elements, §3.3).
  const double z0 = side + 0.37 * kH, z1 = side - 2.63 * kH;
  Vec3 a(centre.x() - 4.9 * kH, centre.y() - 3.9 * kH, z0);
  int dir = 1, moves_in_row = 0, tri = 0;
  Index tested = 0, faces = 0, full_checks = 0;
  for (auto _ : state) {
    const Vec3 step =
        moves_in_row < 16 ? Vec3(dir * 0.5 * kH, 0.013 * kH, 0) : Vec3(0.02 * kH, 0.5 * kH, 0);
    const Vec3 a2 = a + step;
    const Vec3 b(a.x(), a.y(), z1), b2(a2.x(), a2.y(), z1);
    const incise::cut::CutStepReport r =
        (tri % 2 == 0) ? cutter.step(a, b, b2) : cutter.step(a, b2, a2);
    tested += r.elements_tested;
    faces += r.faces_dissected;
    full_checks += r.full_component_check ? 1 : 0;
    if (tri % 2 == 1) {
      a = a2;
      if (++moves_in_row == 20) {
        moves_in_row = 0;
        dir = -dir;
      }
    }
    ++tri;
  }
  state.counters["tets"] = static_cast<double>(mesh.num_elements());
  state.counters["tested_per_step"] = static_cast<double>(tested) / static_cast<double>(tri);
  state.counters["full_component_checks"] = static_cast<double>(full_checks);
  state.counters["faces_per_step"] = static_cast<double>(faces) / static_cast<double>(tri);
}

// 6·12³ = 10 368 and 6·26³ = 105 456 tetrahedra.
BENCHMARK(BM_CutStep)
    ->Args({12, 0})
    ->Args({26, 0})
    ->Args({12, 1})
    ->Args({26, 1})
    ->Iterations(kTriangles)
    ->Unit(benchmark::kMicrosecond);

/// A whole interactive step on the 10k mesh: one sweep triangle, then the solver update — the
/// elastic problem rebuilt from the cut mesh (fem::ElasticProblem has no incremental update,
/// so this part is O(n)) and linear CG (ν = 1/4, ‖r‖ < 1e-3‖f_ex‖, §3.3) restarted warm from
/// the carried displacements. Counters: CG iterations per step.
void BM_InteractiveStep(benchmark::State& state) {
  const int n = 12;
  const double side = n * kH;
  incise::cut::CutMesh mesh(incise::mesh::make_box(n, n, n, side, side, side));
  for (Index v = 0; v < mesh.num_nodes(); ++v)
    if (mesh.reference(v).z() == 0.0) mesh.set_fixed(v, true);
  incise::cut::CutOptions opt;
  incise::cut::Cutter cutter(mesh, opt);
  const incise::material::Material material("linear", {1e4, 0.25, 0.0, 1000.0});
  long cg_iterations = 0;
  auto solve = [&]() {
    std::vector<Index> map;
    const incise::mesh::MeshData md = mesh.to_mesh_data(false, true, &map);
    incise::fem::ElasticProblem p(md, material);
    std::vector<Index> fixed;
    incise::VecX u = incise::VecX::Zero(p.size());
    for (Index v = 0; v < mesh.num_nodes(); ++v) {
      const Index m = map[static_cast<size_t>(v)];
      if (m < 0) continue;
      if (mesh.fixed(v)) fixed.push_back(m);
      u.segment<3>(3 * m) = mesh.deformed(v) - mesh.reference(v);
      // Dilating load on the side faces x = 0 and x = side (original nodes only).
      if (v < (n + 1) * (n + 1) * (n + 1)) {
        const double x = mesh.reference(v).x();
        if (x == 0.0 || x == side) p.add_point_load({m, Vec3(x == 0.0 ? -0.5 : 0.5, 0, 0)});
      }
    }
    p.fix_nodes(fixed);
    p.project(u);
    incise::solver::LinearCgOptions cg;
    cg.stop.rule = incise::solver::ResidualRule::kExternalForce;
    cg.stop.epsilon = 1e-3;
    cg.budget.max_iterations = 20000;
    const incise::solver::SolverReport r = incise::solver::linear_cg(p, u, cg);
    cg_iterations += r.iterations;
    Eigen::Matrix3Xd x = mesh.reference_matrix();
    for (Index v = 0; v < mesh.num_nodes(); ++v) {
      const Index m = map[static_cast<size_t>(v)];
      if (m >= 0) x.col(v) += u.segment<3>(3 * m);
    }
    mesh.set_deformed(x);
  };
  solve();
  cg_iterations = 0;
  Vec3 a(0.3 * side, 0.2 * side, side + 0.37 * kH);
  int tri = 0;
  for (auto _ : state) {
    const Vec3 a2 = a + Vec3(0.5 * kH, 0.01 * kH, 0);
    const Vec3 b(a.x(), a.y(), side - 2.63 * kH), b2(a2.x(), a2.y(), side - 2.63 * kH);
    const incise::cut::CutStepReport r =
        (tri % 2 == 0) ? cutter.step(a, b, b2) : cutter.step(a, b2, a2);
    benchmark::DoNotOptimize(r.faces_dissected);
    solve();
    if (tri % 2 == 1) a = a2;
    ++tri;
  }
  state.counters["cg_iterations_per_step"] =
      static_cast<double>(cg_iterations) / static_cast<double>(tri);
  state.counters["tets"] = static_cast<double>(mesh.num_elements());
}

BENCHMARK(BM_InteractiveStep)->Iterations(20)->Unit(benchmark::kMillisecond);

/// A whole interactive step with the augmented solver (cut/augmented_cut_session.hpp): one
/// sweep triangle, the translation of its CutStepReport into column replacements of the
/// augmented system (Yeung et al. 2016 §3) and the augmented solve of the linear static problem
/// (ν = 1/4, bottom face fixed, dilating load on x = 0 and x = side), without refactoring; the
/// deformed positions are updated after every solve. Arg 0: cells per side (12: 10 368 tets,
/// 26: 105 456 tets). The same blade path as BM_InteractiveStep. Counters (per step, CPU time
/// of this thread): cut_us = Cutter::step (with the search-grid rebuild the deformed update
/// causes), update_ms = column replacements + solve; m, GMRES iterations; setup_s = K⁰
/// factorization + first solve (outside the timed loop); gmres_wall_ms = step 2 (with
/// kDirectCached: the new entries of G, the explicit matrix, its LU and GMRES). Args: cells per
/// side, simplicial factor, deformed update after each solve, explicit H R⁻¹ J.
void BM_AugmentedInteractiveStep(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const double side = n * kH;
  const incise::mesh::MeshData box = incise::mesh::make_box(n, n, n, side, side, side);
  std::vector<Index> fixed;
  Eigen::Matrix3Xd forces = Eigen::Matrix3Xd::Zero(3, box.num_points());
  for (Index v = 0; v < box.num_points(); ++v) {
    const Vec3 p = box.points.col(v);
    if (p.z() == 0.0) fixed.push_back(v);
    if (p.x() == 0.0) forces(0, v) = -0.5;
    if (p.x() == side) forces(0, v) = 0.5;
  }
  const incise::material::Material material("linear", {1e4, 0.25, 0.0, 1000.0});
  incise::interactive::AugmentedCutOptions opt;
  if (state.range(1) != 0) opt.augmented.cholmod.kind = incise::linalg::CholmodKind::kSimplicialLdl;
  opt.update_deformed = state.range(2) != 0;
  opt.augmented.schur_solver = state.range(3) != 0 ? incise::linalg::SchurSolver::kDirectCached
                                                   : incise::linalg::SchurSolver::kGmres;
  incise::interactive::AugmentedCutSession session(box, material, fixed, forces, opt);
  if (!session.initial_report().ok()) {
    state.SkipWithError(session.initial_report().message.c_str());
    return;
  }
  Vec3 a(0.3 * side, 0.2 * side, side + 0.37 * kH);
  int tri = 0;
  double cut_cpu = 0, update_cpu = 0;
  long gmres = 0, failures = 0;
  int m = 0;
  double step2 = 0, step3 = 0;
  for (auto _ : state) {
    const Vec3 a2 = a + Vec3(0.5 * kH, 0.01 * kH, 0);
    const Vec3 b(a.x(), a.y(), side - 2.63 * kH), b2(a2.x(), a2.y(), side - 2.63 * kH);
    const incise::interactive::AugmentedCutStepReport r =
        (tri % 2 == 0) ? session.step(a, b, b2) : session.step(a, b2, a2);
    cut_cpu += r.cpu_seconds_cut;
    update_cpu += r.cpu_seconds_update;
    gmres += r.solve.gmres.iterations;
    failures += r.ok() ? 0 : 1;
    m = r.solved ? r.solve.m : m;
    step2 += r.solve.seconds_step2;
    step3 += r.solve.seconds_step3;
    if (tri % 2 == 1) a = a2;
    ++tri;
  }
  const double steps = static_cast<double>(tri);
  state.counters["tets"] = static_cast<double>(session.mesh().num_elements());
  state.counters["cut_us"] = 1e6 * cut_cpu / steps;
  state.counters["update_ms"] = 1e3 * update_cpu / steps;
  state.counters["gmres_per_step"] = static_cast<double>(gmres) / steps;
  state.counters["m_final"] = m;
  state.counters["failed_steps"] = static_cast<double>(failures);
  state.counters["setup_s"] = session.initial_report().cpu_seconds_update;
  state.counters["gmres_wall_ms"] = 1e3 * step2 / steps;
  state.counters["step3_wall_ms"] = 1e3 * step3 / steps;
}

// Args: cells per side, simplicial factor (0: the session's default supernodal factor),
// deformed update, eq. 17 preconditioned by the explicit H R⁻¹ J (1: the session's default
// SchurSolver::kDirectCached; 0: GMRES + HSJ, the paper's method). The simplicial 100k case is
// left out (≈ 48 s CPU to factor; docs/cutting.md).
BENCHMARK(BM_AugmentedInteractiveStep)
    ->Args({12, 0, 1, 1})
    ->Args({26, 0, 1, 1})
    ->Args({12, 1, 1, 1})
    ->Args({12, 0, 0, 1})
    ->Args({26, 0, 0, 1})
    ->Args({12, 0, 1, 0})
    ->Args({26, 0, 1, 0})
    ->Iterations(40)
    ->Unit(benchmark::kMillisecond);

}  // namespace

INCISE_BENCHMARK_MAIN();
