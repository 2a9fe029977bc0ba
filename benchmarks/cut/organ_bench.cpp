/// Interactive cutting at organ scale (issue 17): the shipped CGAL liver (16,597 tetrahedra)
/// and the same liver refined once by mesh::refine_uniform (Bey 1995, 132,776 tetrahedra) on
/// the scripted path of fixtures/organ_path.hpp (supports and load of liver_pull.json, linear
/// material, a vertical blade half-way down following a circle) at 1, 3 or 10 mm per frame. One
/// frame = one blade advance = two sweep triangles, each followed by the augmented solve
/// (AugmentedCutSession::step) or both followed by one (AugmentedCutSession::frame; last arg).
/// Each benchmark is one run of the whole path (Iterations(1)); the counters are per-frame
/// statistics of wall time: cut (Cutter::step, incl. the deformed-grid update), solver update
/// (column replacements + augmented solve + deformed positions) and frame = their sum; median,
/// p95, max. Frame rate target: median ≤ 33 ms, max ≤ 100 ms. The machine is shared: compare
/// ratios within one run.
///
/// Wall times are reported with the thread CPU times beside them (cpu_*: CLOCK_THREAD_CPUTIME_ID
/// of the frame's thread; they do not grow when other jobs share the cores, wall times do).
///
/// Args: refined (0/1), blade advance per frame (0.1 mm units), frames, refactor_at_m (0: the
/// automatic §3.6 policy), capacitance updated (1) or refactored at every solve (0), and the
/// automatic policy's mode (0 continuous, the default; 1 break-even;
/// interactive/refactorization_policy.hpp), AugmentedOptions::prepare_swap (1, the default), and
/// AugmentedOptions::blas_kernels (1, the default; 0: Eigen's LU and entry-by-entry blocked
/// solves), and AugmentedOptions::overlap_stale_columns (0, the default: one background job at a
/// time; > 0: a second job may start once that many columns changed since the pending one's
/// snapshot), and the solves per frame: 0 one after each sweep triangle (AugmentedCutSession::step,
/// twice per frame), 1 one per frame (AugmentedCutSession::frame: both triangles cut in the
/// deformed configuration of the last frame, then one solve), and AugmentedCutOptions::
/// poll_after_solve (0 off, 1 on), and AugmentedOptions::prepare_in_job (0: the finished
/// factorization waits for a poll before G is prepared; 1, the default: the job goes on to G
/// itself; docs/augmented.md "Preparation in the job"), and AugmentedOptions::
/// eliminate_constrained (1, the default; 0: 𝓓 stays in 𝓛 after a swap), and AugmentedCutOptions::
/// synchronous_refactorization (1, the default: on, with the extended ordering; 2 on with AMD, 3
/// on with METIS; 0 off; docs/augmented.md "Synchronous refactorization"). chg_* counters: frames
/// that solved (the others reuse the last solution and cost the cut); bg_cpu_*: CPU of the
/// background factorizations that were swapped in (their own thread). With INCISE_ORGAN_TRACE=<dir>
/// the per-frame numbers go to <dir>/<benchmark args>.csv, with the cost rule's inputs of the
/// capacitance factorization and, on swap frames, the thread CPU split of the swapped-in job.

#include <benchmark/benchmark.h>
#include <incise/core/problem.hpp>
#include <incise/core/timer.hpp>
#include <incise/fixtures/organ_path.hpp>
#include <incise/interactive/augmented_cut_session.hpp>
#include <incise/io/read_mesh.hpp>
#include <incise/linalg/capacitance_factor.hpp>
#include <incise/linalg/cholmod_factor.hpp>
#include <incise/linalg/dense_blas.hpp>
#include <incise/linalg/ldl_closure_solver.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/quality.hpp>
#include <incise/mesh/refine_uniform.hpp>
#include <incise/solver/linear_cg.hpp>
#include <incise_bench/context.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

namespace {

using incise::Index;
using incise::Vec3;

const incise::mesh::MeshData& liver(bool refined) {
  static const incise::mesh::MeshData coarse = [] {
    incise::io::ReadOptions o;
    o.scale = 0.001;
    return incise::io::read_mesh(
               std::string(INCISE_SOURCE_DIR) + "/reference_data/meshes/liver_coarse.mesh", o)
        .mesh;
  }();
  static const incise::mesh::MeshData fine = incise::mesh::refine_uniform(coarse);
  return refined ? fine : coarse;
}

/// Median, 95th percentile (nearest rank) and maximum: mesh::summarize.
using incise::mesh::summarize;

/// Counters <prefix>_med_ms, <prefix>_p95_ms and <prefix>_max_ms of per-frame times (seconds).
void put_ms_summary(benchmark::State& state, const std::string& prefix,
                    const std::vector<double>& seconds) {
  const auto s = summarize(seconds);
  state.counters[prefix + "_med_ms"] = 1e3 * s.median;
  state.counters[prefix + "_p95_ms"] = 1e3 * s.p95;
  state.counters[prefix + "_max_ms"] = 1e3 * s.max;
}

/// The augmented solves' split, summed over the solves of a frame or of the whole path.
struct SolveTimes {
  double seconds_setup = 0, seconds_step1 = 0, seconds_step2 = 0, seconds_step3 = 0,
         seconds_new_columns = 0, seconds_product = 0, seconds_capfactor = 0, seconds_swap = 0,
         new_columns = 0;
  int solves = 0, fresh = 0, gmres_iterations = 0, rank = 0, needed_rank = 0;
  double update_flops = 0, fresh_flops = 0;  // of the solve with the largest needed rank
  void add(const incise::linalg::AugmentedReport& s) {
    ++solves;
    seconds_setup += s.seconds_setup;
    seconds_step1 += s.seconds_step1;
    seconds_step2 += s.seconds_step2;
    seconds_step3 += s.seconds_step3;
    seconds_new_columns += s.seconds_new_columns;
    seconds_product += s.seconds_capacitance_product;
    seconds_capfactor += s.seconds_capacitance_factor;
    seconds_swap += s.seconds_swap;
    new_columns += s.schur_solves;
    fresh += s.capacitance_refreshed ? 1 : 0;
    gmres_iterations += s.gmres.iterations;
    rank = std::max(rank, s.capacitance_rank);
    if (s.capacitance_needed_rank >= needed_rank) {
      needed_rank = s.capacitance_needed_rank;
      update_flops = s.capacitance_update_flops;
      fresh_flops = s.capacitance_fresh_flops;
    }
  }
};

void BM_LiverScalpelPath(benchmark::State& state) {
  const bool refined = state.range(0) != 0;
  const double advance = 1e-4 * static_cast<double>(state.range(1));  // m per frame
  const int frames = static_cast<int>(state.range(2));
  const incise::mesh::MeshData& body = liver(refined);
  const incise::fixtures::OrganPath path = incise::fixtures::organ_path(body);
  const incise::material::Material material = incise::fixtures::organ_material();
  incise::interactive::AugmentedCutOptions opt;
  opt.refactor_at_m = static_cast<int>(state.range(3));
  opt.augmented.update_capacitance = state.range(4) != 0;
  opt.augmented.prepare_swap = state.range(6) != 0;
  opt.augmented.blas_kernels = state.range(7) != 0;
  opt.augmented.overlap_stale_columns = static_cast<int>(state.range(8));
  const bool per_frame = state.range(9) != 0;
  opt.poll_after_solve = state.range(10) != 0;
  opt.augmented.prepare_in_job = state.range(11) != 0;
  opt.augmented.eliminate_constrained = state.range(12) != 0;
  opt.synchronous_refactorization = state.range(13) != 0;
  if (state.range(13) == 2) opt.synchronous_ordering = incise::linalg::RefactorOrdering::kAmd;
  if (state.range(13) == 3) opt.synchronous_ordering = incise::linalg::RefactorOrdering::kOptions;
  opt.refactorization_mode = state.range(5) == 0
                                 ? incise::interactive::RefactorizationMode::kContinuous
                                 : incise::interactive::RefactorizationMode::kBreakEven;
  for (auto _ : state) {
    incise::interactive::AugmentedCutSession session(body, material, path.fixed, path.forces, opt);
    if (!session.initial_report().ok()) {
      state.SkipWithError(session.initial_report().message.c_str());
      return;
    }
    std::vector<double> cut, update, frame, cut_cpu, update_cpu, frame_cpu;
    int failed = 0, swaps = 0, m_max = 0, m_before_max = 0, refreshed = 0, updated = 0;
    double bg_cpu = 0, bg_wall = 0;
    std::vector<double> chg_frame_cpu, m_after;
    std::ofstream trace;
    if (const char* dir = std::getenv("INCISE_ORGAN_TRACE")) {
      std::string name = std::string(dir) + "/scalpel";
      for (int a = 0; a < 14; ++a) name += "_" + std::to_string(state.range(a));
      trace.open(name + ".csv");
      trace << "frame,cut_cpu_ms,update_cpu_ms,m_before,m_after,swapped,started,new_columns,"
               "newcol_ms,capfactor_ms,cap_fresh,bg_cpu_ms,dirichlet,product_ms,setup_ms,step1_ms,"
               "step2_ms,step3_ms,swap_ms,gmres_iterations,cap_rank,cap_needed_rank,"
               "cap_update_gflop,cap_fresh_gflop,bg_analyze_ms,bg_factorize_ms,"
               "bg_extract_ms,bg_prepare_ms,dirichlet_eliminated,sync\n";
    }
    SolveTimes total;
    for (int f = 0; f < frames; ++f) {
      const auto tris = path.frame(f, advance);
      double c = 0, u = 0, cc = 0, uc = 0, bgc = 0;
      int mb = 0, ma = 0, sw = 0, st = 0, dir = 0, dir_elim = 0, sync = 0;
      SolveTimes in_frame;
      bool solved = false;
      // One solve per frame (AugmentedCutSession::frame) or one per sweep triangle (step).
      std::vector<incise::interactive::AugmentedCutStepReport> reports;
      if (per_frame) {
        reports.push_back(session.frame(tris));
      } else {
        for (const auto& tri : tris) reports.push_back(session.step(tri));
      }
      for (const incise::interactive::AugmentedCutStepReport& r : reports) {
        solved = solved || r.solved;
        if (r.solved) {
          mb = std::max(mb, r.m_before_solve);
          ma = r.m_after_solve;
          dir = r.solve.dirichlet;
          dir_elim = r.solve.dirichlet_eliminated;
          in_frame.add(r.solve);
          total.add(r.solve);
          st += r.refactorization_started ? 1 : 0;
          sync += r.synchronous_refactorization ? 1 : 0;
        }
        if (r.refactorization_swapped) {
          ++sw;
          bgc += session.system().factorization_cpu_seconds();
          bg_cpu += session.system().factorization_cpu_seconds();
          bg_wall += session.system().factorization_seconds();
        }
        c += r.seconds_cut;
        u += r.seconds_update + r.seconds_solve;
        cc += r.cpu_seconds_cut;
        uc += r.cpu_seconds_update;
        failed += r.ok() ? 0 : 1;
        swaps += r.refactorization_swapped ? 1 : 0;
        m_max = std::max(m_max, r.m_after_solve);
        m_before_max = std::max(m_before_max, r.m_before_solve);
        if (r.solved && r.solve.m > 0) (r.solve.capacitance_refreshed ? refreshed : updated) += 1;
      }
      cut.push_back(c);
      update.push_back(u);
      frame.push_back(c + u);
      cut_cpu.push_back(cc);
      update_cpu.push_back(uc);
      frame_cpu.push_back(cc + uc);
      if (solved) {
        chg_frame_cpu.push_back(cc + uc);
        m_after.push_back(ma);
      }
      const incise::linalg::FactorizationCpu split =
          sw > 0 ? session.system().factorization_cpu() : incise::linalg::FactorizationCpu{};
      if (trace.is_open())
        trace << f << ',' << 1e3 * cc << ',' << 1e3 * uc << ',' << mb << ',' << ma << ',' << sw
              << ',' << st << ',' << in_frame.new_columns << ','
              << 1e3 * in_frame.seconds_new_columns << ',' << 1e3 * in_frame.seconds_capfactor
              << ',' << in_frame.fresh << ',' << 1e3 * bgc << ',' << dir << ','
              << 1e3 * in_frame.seconds_product << ',' << 1e3 * in_frame.seconds_setup << ','
              << 1e3 * in_frame.seconds_step1 << ',' << 1e3 * in_frame.seconds_step2 << ','
              << 1e3 * in_frame.seconds_step3 << ',' << 1e3 * in_frame.seconds_swap << ','
              << in_frame.gmres_iterations << ',' << in_frame.rank << ',' << in_frame.needed_rank
              << ',' << 1e-9 * in_frame.update_flops << ',' << 1e-9 * in_frame.fresh_flops << ','
              << 1e3 * split.analyze << ',' << 1e3 * split.factorize << ',' << 1e3 * split.extract
              << ',' << 1e3 * split.prepare << ',' << dir_elim << ',' << sync << std::endl;
    }
    state.counters["chg_frames"] = static_cast<double>(chg_frame_cpu.size());
    put_ms_summary(state, "chg_cpu_frame", chg_frame_cpu);
    state.counters["m_med"] = summarize(m_after).median;
    state.counters["bg_cpu_total_s"] = bg_cpu;
    state.counters["bg_cpu_mean_ms"] = swaps > 0 ? 1e3 * bg_cpu / swaps : 0;
    state.counters["bg_wall_mean_ms"] = swaps > 0 ? 1e3 * bg_wall / swaps : 0;
    put_ms_summary(state, "cpu_cut", cut_cpu);
    put_ms_summary(state, "cpu_upd", update_cpu);
    put_ms_summary(state, "cpu_frame", frame_cpu);
    state.counters["tets"] = static_cast<double>(body.num_cells());
    state.counters["frames"] = frames;
    put_ms_summary(state, "cut", cut);
    put_ms_summary(state, "upd", update);
    put_ms_summary(state, "frame", frame);
    state.counters["m_max"] = m_max;
    state.counters["m_before_max"] = m_before_max;
    state.counters["swaps"] = swaps;
    state.counters["gmres_per_frame"] = static_cast<double>(total.gmres_iterations) / frames;
    state.counters["failed_steps"] = failed;
    state.counters["cap_updated"] = updated;
    state.counters["cap_fresh"] = refreshed;
    state.counters["solves"] = total.solves;
    state.counters["mean_setup_ms"] = 1e3 * total.seconds_setup / frames;
    state.counters["mean_step1_ms"] = 1e3 * total.seconds_step1 / frames;
    state.counters["mean_step2_ms"] = 1e3 * total.seconds_step2 / frames;
    state.counters["mean_step3_ms"] = 1e3 * total.seconds_step3 / frames;
    state.counters["new_columns_per_frame"] = total.new_columns / frames;
    state.counters["mean_newcol_ms"] = 1e3 * total.seconds_new_columns / frames;
    state.counters["mean_product_ms"] = 1e3 * total.seconds_product / frames;
    state.counters["mean_capfactor_ms"] = 1e3 * total.seconds_capfactor / frames;
    state.counters["abandoned"] = session.system().refactorizations_abandoned();
    state.counters["sync_refactors"] = session.synchronous_refactorizations();
    state.counters["grid_builds"] = static_cast<double>(session.cutter().grid_builds());
    state.counters["grid_reentries"] = static_cast<double>(session.cutter().grid_reentries());
  }
}

// Both livers at 1, 3 and 10 mm per frame, 100 frames, the session's defaults (automatic
// §3.6 policy, capacitance updated); at 3 mm also the capacitance LU made afresh at every solve
// (before issue 17) for the ratio in one run. The refined liver takes minutes per path. Then
// overlapping background jobs on stale snapshots (AugmentedOptions::overlap_stale_columns). The
// rows above solve after every sweep triangle (tenth arg 0); then one solve per frame
// (AugmentedCutSession::frame, tenth arg 1) on both livers, and the refined liver's shorter paths
// (10 and 30 frames) both ways; all of these with poll_after_solve off (last arg 0). Last: the
// session's defaults since "One solve per frame" (docs/augmented.md) — poll_after_solve on —
// per triangle and per frame on both livers; the frame of that section is the one-solve frame
// (…/0/1/1/). Every row has the synchronous refactorization on (last arg 1); the last three rows
// are the defaults with it off, then at 10 mm with AMD and METIS orderings for it, for the
// comparison of "Synchronous refactorization".
BENCHMARK(BM_LiverScalpelPath)
    ->Args({0, 10, 100, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 1})
    ->Args({0, 10, 100, 0, 1, 0, 1, 0, 0, 0, 0, 1, 1, 1})
    ->Args({0, 30, 100, 0, 1, 0, 1, 0, 0, 0, 0, 1, 1, 1})
    ->Args({0, 100, 100, 0, 1, 0, 1, 0, 0, 0, 0, 1, 1, 1})
    ->Args({0, 10, 100, 0, 1, 1, 1, 1, 0, 0, 0, 1, 1, 1})
    ->Args({0, 30, 100, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 1})
    ->Args({0, 30, 100, 0, 1, 1, 1, 1, 0, 0, 0, 1, 1, 1})
    ->Args({0, 30, 100, 0, 0, 0, 1, 1, 0, 0, 0, 1, 1, 1})
    ->Args({0, 100, 100, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 1})
    ->Args({0, 100, 100, 0, 1, 1, 1, 1, 0, 0, 0, 1, 1, 1})
    ->Args({0, 10, 100, 0, 1, 0, 0, 1, 0, 0, 0, 1, 1, 1})
    ->Args({0, 10, 100, 0, 1, 1, 0, 1, 0, 0, 0, 1, 1, 1})
    ->Args({0, 30, 100, 0, 1, 0, 0, 1, 0, 0, 0, 1, 1, 1})
    ->Args({0, 30, 100, 0, 1, 1, 0, 1, 0, 0, 0, 1, 1, 1})
    ->Args({0, 100, 100, 0, 1, 0, 0, 1, 0, 0, 0, 1, 1, 1})
    ->Args({0, 100, 100, 0, 1, 1, 0, 1, 0, 0, 0, 1, 1, 1})
    ->Args({0, 30, 30, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 1})
    ->Args({1, 30, 30, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 1})
    ->Args({0, 10, 100, 0, 1, 0, 1, 1, 150, 0, 0, 1, 1, 1})
    ->Args({0, 10, 100, 0, 1, 0, 1, 1, 300, 0, 0, 1, 1, 1})
    ->Args({0, 10, 100, 0, 1, 0, 1, 1, 600, 0, 0, 1, 1, 1})
    ->Args({0, 30, 100, 0, 1, 0, 1, 1, 150, 0, 0, 1, 1, 1})
    ->Args({0, 30, 100, 0, 1, 0, 1, 1, 300, 0, 0, 1, 1, 1})
    ->Args({0, 30, 100, 0, 1, 0, 1, 1, 600, 0, 0, 1, 1, 1})
    ->Args({0, 100, 100, 0, 1, 0, 1, 1, 150, 0, 0, 1, 1, 1})
    ->Args({0, 100, 100, 0, 1, 0, 1, 1, 300, 0, 0, 1, 1, 1})
    ->Args({0, 100, 100, 0, 1, 0, 1, 1, 600, 0, 0, 1, 1, 1})
    ->Args({1, 10, 100, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 1})
    ->Args({1, 30, 100, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 1})
    ->Args({1, 30, 100, 0, 0, 0, 1, 1, 0, 0, 0, 1, 1, 1})
    ->Args({1, 100, 100, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 1})
    ->Args({0, 10, 100, 0, 1, 0, 1, 1, 0, 1, 0, 1, 1, 1})
    ->Args({0, 30, 100, 0, 1, 0, 1, 1, 0, 1, 0, 1, 1, 1})
    ->Args({0, 100, 100, 0, 1, 0, 1, 1, 0, 1, 0, 1, 1, 1})
    ->Args({1, 10, 10, 0, 1, 0, 1, 1, 0, 1, 0, 1, 1, 1})
    ->Args({1, 30, 10, 0, 1, 0, 1, 1, 0, 1, 0, 1, 1, 1})
    ->Args({1, 100, 10, 0, 1, 0, 1, 1, 0, 1, 0, 1, 1, 1})
    ->Args({1, 10, 30, 0, 1, 0, 1, 1, 0, 1, 0, 1, 1, 1})
    ->Args({1, 30, 30, 0, 1, 0, 1, 1, 0, 1, 0, 1, 1, 1})
    ->Args({1, 100, 30, 0, 1, 0, 1, 1, 0, 1, 0, 1, 1, 1})
    ->Args({1, 10, 100, 0, 1, 0, 1, 1, 0, 1, 0, 1, 1, 1})
    ->Args({1, 30, 100, 0, 1, 0, 1, 1, 0, 1, 0, 1, 1, 1})
    ->Args({1, 100, 100, 0, 1, 0, 1, 1, 0, 1, 0, 1, 1, 1})
    ->Args({1, 10, 10, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 1})
    ->Args({1, 30, 10, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 1})
    ->Args({1, 100, 10, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 1})
    ->Args({1, 10, 30, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 1})
    ->Args({1, 100, 30, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 1})
    ->Args({0, 10, 100, 0, 1, 0, 1, 1, 0, 0, 1, 1, 1, 1})
    ->Args({0, 30, 100, 0, 1, 0, 1, 1, 0, 0, 1, 1, 1, 1})
    ->Args({0, 100, 100, 0, 1, 0, 1, 1, 0, 0, 1, 1, 1, 1})
    ->Args({1, 10, 10, 0, 1, 0, 1, 1, 0, 1, 1, 1, 1, 1})
    ->Args({1, 30, 10, 0, 1, 0, 1, 1, 0, 1, 1, 1, 1, 1})
    ->Args({1, 100, 10, 0, 1, 0, 1, 1, 0, 1, 1, 1, 1, 1})
    ->Args({1, 10, 100, 0, 1, 0, 1, 1, 0, 0, 1, 1, 1, 1})
    ->Args({1, 30, 100, 0, 1, 0, 1, 1, 0, 0, 1, 1, 1, 1})
    ->Args({1, 100, 100, 0, 1, 0, 1, 1, 0, 0, 1, 1, 1, 1})
    ->Args({0, 10, 100, 0, 1, 0, 1, 1, 0, 1, 1, 0, 1, 1})
    ->Args({0, 30, 100, 0, 1, 0, 1, 1, 0, 1, 1, 0, 1, 1})
    ->Args({0, 100, 100, 0, 1, 0, 1, 1, 0, 1, 1, 0, 1, 1})
    ->Args({0, 10, 100, 0, 1, 0, 1, 1, 0, 1, 1, 1, 1, 1})
    ->Args({0, 30, 100, 0, 1, 0, 1, 1, 0, 1, 1, 1, 1, 1})
    ->Args({0, 100, 100, 0, 1, 0, 1, 1, 0, 1, 1, 1, 1, 1})
    ->Args({0, 10, 100, 0, 1, 0, 1, 1, 0, 1, 1, 1, 0, 1})
    ->Args({0, 30, 100, 0, 1, 0, 1, 1, 0, 1, 1, 1, 0, 1})
    ->Args({0, 100, 100, 0, 1, 0, 1, 1, 0, 1, 1, 1, 0, 1})
    ->Args({1, 10, 100, 0, 1, 0, 1, 1, 0, 1, 1, 0, 1, 1})
    ->Args({1, 30, 100, 0, 1, 0, 1, 1, 0, 1, 1, 0, 1, 1})
    ->Args({1, 100, 100, 0, 1, 0, 1, 1, 0, 1, 1, 0, 1, 1})
    ->Args({1, 10, 100, 0, 1, 0, 1, 1, 0, 1, 1, 1, 1, 1})
    ->Args({1, 30, 100, 0, 1, 0, 1, 1, 0, 1, 1, 1, 1, 1})
    ->Args({1, 100, 100, 0, 1, 0, 1, 1, 0, 1, 1, 1, 1, 1})
    ->Args({0, 10, 100, 0, 1, 0, 1, 1, 0, 1, 1, 1, 1, 0})
    ->Args({0, 30, 100, 0, 1, 0, 1, 1, 0, 1, 1, 1, 1, 0})
    ->Args({0, 100, 100, 0, 1, 0, 1, 1, 0, 1, 1, 1, 1, 0})
    ->Args({0, 100, 100, 0, 1, 0, 1, 1, 0, 1, 1, 1, 1, 2})
    ->Args({0, 100, 100, 0, 1, 0, 1, 1, 0, 1, 1, 1, 1, 3})
    ->Iterations(1)
    ->Unit(benchmark::kSecond);

// The cut step alone on the path (issue 17's "cut step independent of the mesh size"): a
// cut::Cutter with the session's cut options on the liver or the refined liver, nodes kept at
// their reference positions (no solve, so no drift and one grid build), per-frame thread CPU of
// the two Cutter::step calls. Separates the cost that grows with the faces the blade crosses
// (elements tested, faces dissected: ≈ 4× on the 1→8 refined mesh, whose faces per swept area are
// 4×) from the mesh-size cost of the deformed-configuration loop (BM_LiverScalpelPath). Args:
// refined (0/1), blade advance per frame (0.1 mm units), frames.
void BM_LiverCutOnly(benchmark::State& state) {
  const incise::mesh::MeshData& body = liver(state.range(0) != 0);
  const double advance = 1e-4 * static_cast<double>(state.range(1));
  const int frames = static_cast<int>(state.range(2));
  const incise::fixtures::OrganPath path = incise::fixtures::organ_path(body);
  for (auto _ : state) {
    incise::cut::CutMesh mesh(body);
    for (Index v : path.fixed) mesh.set_fixed(v, true);
    incise::cut::Cutter cutter(mesh, incise::interactive::AugmentedCutOptions{}.cut);
    std::vector<double> cpu, cpu_per_tested, tested, dissected;
    int full_checks = 0;
    for (int f = 0; f < frames; ++f) {
      const auto tris = path.frame(f, advance);
      const double t0 = incise::thread_cpu_seconds();
      Index te = 0, fd = 0;
      for (int k = 0; k < 2; ++k) {
        const incise::cut::CutStepReport r = cutter.step(tris[k][0], tris[k][1], tris[k][2]);
        te += r.elements_tested;
        fd += r.faces_dissected;
        full_checks += r.full_component_check ? 1 : 0;
      }
      const double c = incise::thread_cpu_seconds() - t0;
      cpu.push_back(c);
      tested.push_back(static_cast<double>(te));
      dissected.push_back(static_cast<double>(fd));
      if (te > 0) cpu_per_tested.push_back(c / static_cast<double>(te));
    }
    const auto sc = summarize(cpu), st = summarize(tested), sd = summarize(dissected),
               sp = summarize(cpu_per_tested);
    state.counters["cpu_cut_med_ms"] = 1e3 * sc.median;
    state.counters["cpu_cut_p95_ms"] = 1e3 * sc.p95;
    state.counters["cpu_cut_max_ms"] = 1e3 * sc.max;
    state.counters["tested_med"] = st.median;
    state.counters["dissected_med"] = sd.median;
    state.counters["us_per_tested_med"] = 1e6 * sp.median;
    state.counters["grid_builds"] = static_cast<double>(cutter.grid_builds());
    state.counters["full_component_checks"] = full_checks;
    state.counters["tets"] = static_cast<double>(body.num_cells());
  }
}
BENCHMARK(BM_LiverCutOnly)
    ->Args({0, 30, 30})
    ->Args({1, 30, 30})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

// The k new columns R⁻¹e of G = H R⁻¹ Hᵀ for DOFs joining 𝓛, one restricted solve each (0), one
// blocked pass entry by entry (1) or with its supernode blocks through dgemm/dtrsm (2; both
// ClosureLdlSolver::solve_restricted_block), on the liver's K⁰ factor
// (METIS; simplicial LDLᵀ, or supernodal as the session's defaults — linalg::interactive_options —
// whose LDLᵀ copy has the wide supernodes the blocked pass hands to dgemm/dtrsm): 𝓛 = the DOFs of
// the 300 nodes nearest the path's first blade position (m = 900), k of them joining. CPU time is
// the measure. Args: single / blocked / blocked dense (0/1/2), refined liver, supernodal (0/1), k.
void BM_NewColumnsOfG(benchmark::State& state) {
  const bool blocked = state.range(0) != 0;
  const bool dense = state.range(0) == 2;
  const incise::mesh::MeshData& body = liver(state.range(1) != 0);
  const incise::fixtures::OrganPath path = incise::fixtures::organ_path(body);
  incise::interactive::AugmentedCutOptions opt;
  opt.automatic_refactorization = false;
  incise::interactive::AugmentedCutSession session(body, incise::fixtures::organ_material(),
                                                   path.fixed, path.forces, opt);
  const incise::linalg::SparseMatrix k0 = session.system().current_matrix();
  incise::linalg::CholmodFactor factor({state.range(2) != 0
                                            ? incise::linalg::CholmodKind::kSupernodal
                                            : incise::linalg::CholmodKind::kSimplicialLdl,
                                        incise::linalg::CholmodOrdering::kMetis});
  const auto joining_count = static_cast<std::size_t>(state.range(3) > 0 ? state.range(3) : 40);
  if (factor.compute(k0, 1) != incise::linalg::FactorStatus::kOk) {
    state.SkipWithError("factorization failed");
    return;
  }
  incise::linalg::ClosureLdlSolver solver(factor.extract_ldl());
  const Vec3 blade = path.frame(0, 0.0)[0][1];
  std::vector<std::pair<double, Index>> near;
  for (Index v = 0; v < body.num_points(); ++v)
    if (session.dof(v) >= 0) near.emplace_back((body.points.col(v) - blade).norm(), v);
  std::partial_sort(near.begin(), near.begin() + 300, near.end());
  std::vector<int> l;
  for (int i = 0; i < 300; ++i)
    for (int c = 0; c < 3; ++c)
      l.push_back(session.dof(near[static_cast<std::size_t>(i)].second) + c);
  std::sort(l.begin(), l.end());
  std::vector<int> joining;
  for (std::size_t i = 0; i < l.size() && joining.size() < joining_count;
       i += std::max<std::size_t>(1, l.size() / joining_count))
    joining.push_back(l[i]);
  const std::vector<int> closure_y = solver.closure(l);
  double checksum = 0;
  for (auto _ : state) {
    if (blocked) {
      Eigen::MatrixXd y;
      solver.solve_restricted_block(joining, solver.closure(joining), closure_y, l, y, dense);
      checksum += y(0, 0);
    } else {
      std::vector<double> y;
      for (int j : joining) {
        const std::vector<int> e{j};
        solver.solve_restricted(e, {1.0}, solver.closure(e), closure_y, l, y);
        checksum += y[0];
      }
    }
  }
  benchmark::DoNotOptimize(checksum);
  state.counters["m"] = static_cast<double>(l.size());
  state.counters["k"] = static_cast<double>(joining.size());
  state.counters["closure_y"] = static_cast<double>(closure_y.size());
  state.counters["nnz_l"] = static_cast<double>(factor.extract_ldl()->nnz_l());
}
BENCHMARK(BM_NewColumnsOfG)
    ->Args({0, 0, 0, 40})
    ->Args({1, 0, 0, 40})
    ->Args({2, 0, 0, 40})
    ->Args({0, 1, 0, 40})
    ->Args({1, 1, 0, 40})
    ->Args({2, 1, 0, 40})
    ->Args({0, 0, 1, 40})
    ->Args({1, 0, 1, 40})
    ->Args({2, 0, 1, 40})
    ->Args({0, 0, 1, 150})
    ->Args({1, 0, 1, 150})
    ->Args({2, 0, 1, 150})
    ->Unit(benchmark::kMillisecond);

// The capacitance matrix's dense LU (linalg::DenseLu, the kernel of CapacitanceFactor's fresh
// factorization) at the m the liver path reaches: LAPACK's dgetrf of the loaded BLAS vs Eigen's
// PartialPivLU (SSE2 in this build), factorization + one solve with 100 right-hand sides (the
// W columns of an update). A random well-conditioned matrix (identity + coupling of norm ≤ 0.5).
// CPU time is the measure. Args: m, LAPACK (1) or Eigen (0).
void BM_CapacitanceLu(benchmark::State& state) {
  const auto m = static_cast<Eigen::Index>(state.range(0));
  const Eigen::MatrixXd a =
      Eigen::MatrixXd::Identity(m, m) +
      Eigen::MatrixXd::Random(m, m) * (0.5 / static_cast<double>(m));  // Eigen's fixed seed
  const Eigen::MatrixXd b = Eigen::MatrixXd::Random(m, 100);
  incise::linalg::DenseLu lu(state.range(1) != 0);
  double checksum = 0;
  for (auto _ : state) {
    lu.compute(a);
    Eigen::MatrixXd x = b;
    lu.solve_in_place(x);
    checksum += x(0, 0);
  }
  benchmark::DoNotOptimize(checksum);
  state.counters["lapack"] = lu.uses_blas() ? 1 : 0;
}
// A fresh CapacitanceFactor::update (force_fresh) on the same matrices: equilibration, the LU
// and Hager's condition estimate (≤ 5 iterations of two solves) — what a capacitance refresh
// costs a frame beside the bare LU above. Args: m, LAPACK (1) or Eigen (0).
void BM_CapacitanceFresh(benchmark::State& state) {
  const auto m = static_cast<Eigen::Index>(state.range(0));
  const Eigen::MatrixXd a =
      Eigen::MatrixXd::Identity(m, m) +
      Eigen::MatrixXd::Random(m, m) * (0.5 / static_cast<double>(m));  // Eigen's fixed seed
  std::vector<int> labels(static_cast<std::size_t>(m));
  for (std::size_t i = 0; i < labels.size(); ++i) labels[i] = static_cast<int>(i);
  incise::linalg::CapacitanceFactor factor(1.0, state.range(1) != 0);
  double checksum = 0;
  for (auto _ : state) checksum += factor.update(a, labels, /*force_fresh=*/true).rcond;
  benchmark::DoNotOptimize(checksum);
}
BENCHMARK(BM_CapacitanceFresh)
    ->Args({1000, 0})
    ->Args({1000, 1})
    ->Args({1500, 1})
    ->Unit(benchmark::kMillisecond);

BENCHMARK(BM_CapacitanceLu)
    ->Args({500, 0})
    ->Args({500, 1})
    ->Args({1000, 0})
    ->Args({1000, 1})
    ->Args({1500, 0})
    ->Args({1500, 1})
    ->Unit(benchmark::kMillisecond);

// ---------------------------------------------------------------------------------------------
// Issue 17's side-by-side of per-frame strategies, in one run on the same path. The augmented
// session (defaults) cuts and solves; after every frame its system — K = system().current_matrix()
// (n × n, new DOFs included), f = system().force(), the constrained DOFs 𝓓 with the session's
// prescribed values ā — is written as one SPD system K̃ x = b with the rows and columns of 𝓓
// replaced by their diagonal (b_d = K_dd ā_d; b_i = f_i − Σ_d K_id ā_d), and solved by:
//   refactor  — a fresh CHOLMOD factorization (the session's supernodal METIS options; the
//               symbolic analysis kept while the pattern is unchanged) and a solve;
//   updown    — CholmodFactor::modify (cholmod_updown on a simplicial LDLᵀ of K̃ padded to a
//               DOF reserve with a scaled identity, so that new DOFs are a low-rank change too;
//               a fresh factorization with a doubled reserve when the reserve runs out or a
//               modification fails) of ΔK̃ = K̃_f − K̃_{f−1}, then a solve;
//   cg        — Jacobi-preconditioned CG (solver::projected_cg) on K̃ δ = b − K̃ x_{f−1}, warm
//               started from the previous frame's solution (new DOFs start at 0), stopping at
//               ‖r‖₂ ≤ 1e-8‖b‖₂ (or 20·n iterations).
// Statistics are over the frames that change K̃ or b (the others cost every strategy nothing
// but the cut: the session reuses its solution, and so would the alternatives). Timed: thread CPU
// of the strategy's own work from the assembled K̃ (the assembly and ΔK̃ are bookkeeping of this
// benchmark and not counted; the augmented column replacements are counted in its update). The cut
// is the same for every strategy (the session's); frame = cut + solver. Every changed frame's
// solutions are compared with an independent fresh factorization (CHOLMOD simplicial LDLᵀ, AMD):
// max-norm relative difference.
//   every     — a second session in lockstep with AugmentedCutOptions::refactor_every_step
//               (a library option, no scene key): its own cut and update, i.e. a factorization of
//               the current K in the frame thread and a solve with m = |𝓓| (its solution is
//               compared when its DOF count equals the first session's: the same cut).
// Args: refined (0/1), blade advance per frame (0.1 mm units), frames, the augmented session's
// §3.6 policy mode (0 continuous, the default; 1 break-even). bg_cpu_*: CPU of the swapped-in
// background factorizations (their own thread; not in any frame time).

/// K̃ x = b with 𝓓 eliminated symmetrically (see above); x_d = ā_d.
struct FrameSystem {
  incise::linalg::SparseMatrix k;
  Eigen::VectorXd b;
};

FrameSystem frame_system(const incise::interactive::AugmentedCutSession& session) {
  const incise::linalg::AugmentedSystem& sys = session.system();
  const incise::linalg::SparseMatrix k = sys.current_matrix();
  const int n = sys.num_dofs();
  Eigen::VectorXd abar = Eigen::VectorXd::Zero(n);
  std::vector<char> fixed(static_cast<std::size_t>(n), 0);
  for (Index v = 0; v < session.mesh().num_nodes(); ++v) {
    const int d = session.dof(v);
    if (d < 0) continue;
    for (int c = 0; c < 3; ++c)
      if (sys.is_constrained(d + c)) {
        fixed[static_cast<std::size_t>(d + c)] = 1;
        abar(d + c) = session.displacement()(c, v);
      }
  }
  FrameSystem out;
  out.b = sys.force() - k * abar;
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<std::size_t>(k.nonZeros()));
  for (int j = 0; j < n; ++j) {
    for (incise::linalg::SparseMatrix::InnerIterator it(k, j); it; ++it) {
      const int i = static_cast<int>(it.row());
      if (i == j) {
        t.emplace_back(i, j, it.value() != 0.0 ? it.value() : 1.0);
      } else if (!fixed[static_cast<std::size_t>(i)] && !fixed[static_cast<std::size_t>(j)]) {
        t.emplace_back(i, j, it.value());
      }
    }
  }
  out.k.resize(n, n);
  out.k.setFromTriplets(t.begin(), t.end());
  out.k.makeCompressed();
  for (int d = 0; d < n; ++d)
    if (fixed[static_cast<std::size_t>(d)]) out.b(d) = out.k.coeff(d, d) * abar(d);
  return out;
}

bool same_pattern(const incise::linalg::SparseMatrix& a, const incise::linalg::SparseMatrix& b) {
  return a.rows() == b.rows() && a.nonZeros() == b.nonZeros() &&
         std::equal(a.outerIndexPtr(), a.outerIndexPtr() + a.outerSize() + 1, b.outerIndexPtr()) &&
         std::equal(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros(), b.innerIndexPtr());
}

/// `a` (n × n) padded to order `size` with `scale`·I.
incise::linalg::SparseMatrix padded(const incise::linalg::SparseMatrix& a, int size, double scale) {
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<std::size_t>(a.nonZeros() + size - a.rows()));
  for (int j = 0; j < a.outerSize(); ++j)
    for (incise::linalg::SparseMatrix::InnerIterator it(a, j); it; ++it)
      t.emplace_back(static_cast<int>(it.row()), j, it.value());
  for (int j = static_cast<int>(a.rows()); j < size; ++j) t.emplace_back(j, j, scale);
  incise::linalg::SparseMatrix out(size, size);
  out.setFromTriplets(t.begin(), t.end());
  out.makeCompressed();
  return out;
}

/// The quadratic ½xᵀK̃x − bᵀx as a solver::Problem for projected_cg (no fixed DOFs: 𝓓 is
/// eliminated in K̃; only project() and the products are used by the CG).
class AssembledQuadratic : public incise::Problem {
 public:
  AssembledQuadratic(const incise::linalg::SparseMatrix& k, const Eigen::VectorXd& b)
      : k_(k), b_(b) {}
  Eigen::Index size() const override { return b_.size(); }
  incise::EvalStatus energy(const incise::VecX& u, double& e) override {
    e = 0.5 * u.dot(k_ * u) - b_.dot(u);
    return incise::EvalStatus::kOk;
  }
  incise::EvalStatus gradient(const incise::VecX& u, incise::VecX& g, double* e) override {
    g = k_ * u - b_;
    if (e != nullptr) *e = 0.5 * u.dot(g - b_);
    return incise::EvalStatus::kOk;
  }
  incise::EvalStatus hessian_product(const incise::VecX&, const incise::VecX& d,
                                     incise::VecX& out) override {
    out = k_ * d;
    return incise::EvalStatus::kOk;
  }
  void project(incise::VecX&) const override {}
  bool is_fixed(Eigen::Index) const override { return false; }
  double external_force_norm() const override { return b_.norm(); }

 private:
  const incise::linalg::SparseMatrix& k_;
  const Eigen::VectorXd& b_;
};

/// The session's displacement at its `n` DOFs (the layout of its system's matrix).
Eigen::VectorXd dof_displacement(const incise::interactive::AugmentedCutSession& session, int n) {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  for (Index v = 0; v < session.mesh().num_nodes(); ++v) {
    const int d = session.dof(v);
    if (d >= 0)
      for (int k = 0; k < 3; ++k) x(d + k) = session.displacement()(k, v);
  }
  return x;
}

double max_relative(const Eigen::VectorXd& x, const Eigen::VectorXd& ref) {
  const double scale = ref.cwiseAbs().maxCoeff();
  const double diff = (x.head(ref.size()) - ref).cwiseAbs().maxCoeff();
  return scale > 0 ? diff / scale : diff;
}

void BM_LiverStrategies(benchmark::State& state) {
  using incise::linalg::CholmodFactor;
  using incise::linalg::FactorStatus;
  const bool refined = state.range(0) != 0;
  const double advance = 1e-4 * static_cast<double>(state.range(1));
  const int frames = static_cast<int>(state.range(2));
  const incise::mesh::MeshData& body = liver(refined);
  const incise::fixtures::OrganPath path = incise::fixtures::organ_path(body);
  const incise::material::Material material = incise::fixtures::organ_material();
  incise::interactive::AugmentedCutOptions aug_options;
  aug_options.refactorization_mode = state.range(3) == 0
                                         ? incise::interactive::RefactorizationMode::kContinuous
                                         : incise::interactive::RefactorizationMode::kBreakEven;
  for (auto _ : state) {
    incise::interactive::AugmentedCutSession session(body, material, path.fixed, path.forces,
                                                     aug_options);
    if (!session.initial_report().ok()) {
      state.SkipWithError(session.initial_report().message.c_str());
      return;
    }
    // The same path with AugmentedCutOptions::refactor_every_step, in lockstep.
    incise::interactive::AugmentedCutOptions every;
    every.refactor_every_step = true;
    incise::interactive::AugmentedCutSession session_every(body, material, path.fixed, path.forces,
                                                           every);
    FrameSystem prev = frame_system(session);
    const int n0 = static_cast<int>(prev.k.rows());
    // refactor: the session's factorization options.
    CholmodFactor refactor(incise::interactive::AugmentedCutOptions::supernodal_defaults().cholmod);
    std::uint64_t version = 1;
    // updown: simplicial LDLᵀ of K̃ padded to a reserve of DOFs.
    const double pad_scale = prev.k.diagonal().sum() / n0;
    int reserve = n0 + std::max(300, n0 / 8);
    auto updown = std::make_unique<CholmodFactor>(incise::linalg::CholmodOptions{
        incise::linalg::CholmodKind::kSimplicialLdl, incise::linalg::CholmodOrdering::kMetis});
    if (updown->compute(padded(prev.k, reserve, pad_scale), 1) != FactorStatus::kOk ||
        refactor.compute(prev.k, version) != FactorStatus::kOk) {
      state.SkipWithError("initial factorization failed");
      return;
    }
    Eigen::VectorXd x_cg;
    if (refactor.solve(prev.b, x_cg) != FactorStatus::kOk) {
      state.SkipWithError("initial solve failed");
      return;
    }
    std::vector<double> cut, aug, ref_t, upd_t, cg_t, every_t;
    double err_every = 0;
    int every_mismatch = 0;
    double err_aug = 0, err_ref = 0, err_upd = 0, err_cg = 0, worst_cg_res = 0;
    int changed = 0, updown_refactors = 0, updown_failures = 0, rank_max = 0, touched_max = 0;
    long cg_iterations = 0, cg_iter_max = 0;
    double rank_sum = 0, split_sum = 0, updown_sum = 0, bg_cpu = 0;
    int aug_swaps = 0, aug_m_max = 0;
    bool failed = false;
    for (int f = 0; f < frames && !failed; ++f) {
      double c = 0, u = 0, e = 0;
      for (const auto& tri : path.frame(f, advance)) {
        const incise::interactive::AugmentedCutStepReport r = session.step(tri);
        c += r.cpu_seconds_cut;
        u += r.cpu_seconds_update;
        if (!r.ok()) failed = true;
        if (r.refactorization_swapped) {
          ++aug_swaps;
          bg_cpu += session.system().factorization_cpu_seconds();
        }
        aug_m_max = std::max(aug_m_max, r.m_after_solve);
        const incise::interactive::AugmentedCutStepReport re = session_every.step(tri);
        e += re.cpu_seconds_update;
        if (!re.ok()) failed = true;
      }
      cut.push_back(c);
      aug.push_back(u);
      every_t.push_back(e);
      FrameSystem cur = frame_system(session);
      const bool pattern = same_pattern(cur.k, prev.k);
      const bool unchanged =
          pattern &&
          std::equal(cur.k.valuePtr(), cur.k.valuePtr() + cur.k.nonZeros(), prev.k.valuePtr()) &&
          cur.b == prev.b;
      if (unchanged) {  // statistics over the changed frames only
        cut.pop_back();
        aug.pop_back();
        every_t.pop_back();
        continue;
      }
      ++changed;
      const int n = static_cast<int>(cur.k.rows());
      // Independent reference (not timed).
      CholmodFactor reference(incise::linalg::CholmodOptions{
          incise::linalg::CholmodKind::kSimplicialLdl, incise::linalg::CholmodOrdering::kAmd});
      Eigen::VectorXd x_ref;
      if (reference.compute(cur.k, 1) != FactorStatus::kOk ||
          reference.solve(cur.b, x_ref) != FactorStatus::kOk) {
        state.SkipWithError("reference factorization failed");
        return;
      }
      // Augmented: the session's displacement at the DOFs.
      err_aug = std::max(err_aug, max_relative(dof_displacement(session, n), x_ref));
      if (session_every.system().num_dofs() == n) {  // the same cut (solutions agree to 1e-12)
        err_every = std::max(err_every, max_relative(dof_displacement(session_every, n), x_ref));
      } else {
        ++every_mismatch;
      }
      // Refactor every frame.
      {
        const double t0 = incise::thread_cpu_seconds();
        if (!pattern) ++version;
        Eigen::VectorXd x;
        const bool ok = refactor.compute(cur.k, version) == FactorStatus::kOk &&
                        refactor.solve(cur.b, x) == FactorStatus::kOk;
        ref_t.push_back(incise::thread_cpu_seconds() - t0);
        if (!ok) {
          state.SkipWithError("refactor strategy failed");
          return;
        }
        err_ref = std::max(err_ref, max_relative(x, x_ref));
      }
      // cholmod_updown of the padded factor.
      {
        const incise::linalg::SparseMatrix delta =
            n <= reserve ? incise::linalg::SparseMatrix((padded(cur.k, reserve, pad_scale) -
                                                         padded(prev.k, reserve, pad_scale))
                                                            .pruned())
                         : incise::linalg::SparseMatrix();
        const double t0 = incise::thread_cpu_seconds();
        CholmodFactor::ModifyStats stats;
        bool ok = n <= reserve;
        if (ok) {
          ok = updown->modify(delta, &stats) == FactorStatus::kOk;
          updown_failures += ok ? 0 : 1;
        }
        if (!ok) {  // reserve exhausted or modification failed: a fresh factor
          ++updown_refactors;
          while (reserve < n + 300) reserve *= 2;
          updown = std::make_unique<CholmodFactor>(
              incise::linalg::CholmodOptions{incise::linalg::CholmodKind::kSimplicialLdl,
                                             incise::linalg::CholmodOrdering::kMetis});
          ok = updown->compute(padded(cur.k, reserve, pad_scale), 1) == FactorStatus::kOk;
        }
        Eigen::VectorXd bp = Eigen::VectorXd::Zero(reserve), x;
        bp.head(n) = cur.b;
        ok = ok && updown->solve(bp, x) == FactorStatus::kOk;
        upd_t.push_back(incise::thread_cpu_seconds() - t0);
        if (!ok) {
          state.SkipWithError("updown strategy failed");
          return;
        }
        rank_max = std::max(rank_max, stats.rank_update + stats.rank_downdate);
        rank_sum += stats.rank_update + stats.rank_downdate;
        split_sum += stats.cpu_seconds_split;
        updown_sum += stats.cpu_seconds_updown;
        touched_max = std::max(touched_max, stats.touched);
        err_upd = std::max(err_upd, max_relative(x, x_ref));
      }
      // Warm-started Jacobi-PCG.
      {
        const double t0 = incise::thread_cpu_seconds();
        Eigen::VectorXd x0 = Eigen::VectorXd::Zero(n);
        x0.head(std::min<Eigen::Index>(n, x_cg.size())) =
            x_cg.head(std::min<Eigen::Index>(n, x_cg.size()));
        const Eigen::VectorXd r0 = cur.b - cur.k * x0;
        const Eigen::VectorXd inv_diag = cur.k.diagonal().cwiseInverse();
        AssembledQuadratic q(cur.k, cur.b);
        incise::solver::CostMeter meter(q);
        Eigen::VectorXd dx;
        const incise::solver::InnerCgResult res = incise::solver::projected_cg(
            [&](const incise::VecX& in, incise::VecX& out) {
              out = cur.k * in;
              return incise::EvalStatus::kOk;
            },
            q, inv_diag, r0, dx, 1e-8 * cur.b.norm(), 20L * n, meter);
        x_cg = x0 + dx;
        cg_t.push_back(incise::thread_cpu_seconds() - t0);
        cg_iterations += res.iterations;
        cg_iter_max = std::max(cg_iter_max, res.iterations);
        worst_cg_res = std::max(worst_cg_res, (cur.b - cur.k * x_cg).norm() / cur.b.norm());
        err_cg = std::max(err_cg, max_relative(x_cg, x_ref));
      }
      prev = std::move(cur);
    }
    if (failed) state.counters["session_failed"] = 1;
    const auto put = [&](const std::string& name, const std::vector<double>& solver) {
      std::vector<double> frame(solver.size());
      for (std::size_t i = 0; i < solver.size(); ++i) frame[i] = cut[i] + solver[i];
      const auto s = summarize(solver), fr = summarize(frame);
      state.counters[name + "_med_ms"] = 1e3 * fr.median;
      state.counters[name + "_p95_ms"] = 1e3 * fr.p95;
      state.counters[name + "_max_ms"] = 1e3 * fr.max;
      state.counters[name + "_solver_med_ms"] = 1e3 * s.median;
    };
    put("aug", aug);
    put("refactor", ref_t);
    put("updown", upd_t);
    put("cg", cg_t);
    put("every", every_t);
    state.counters["aug_swaps"] = aug_swaps;
    state.counters["aug_m_max"] = aug_m_max;
    state.counters["bg_cpu_total_s"] = bg_cpu;
    state.counters["bg_cpu_mean_ms"] = aug_swaps > 0 ? 1e3 * bg_cpu / aug_swaps : 0;
    state.counters["err_every"] = err_every;
    state.counters["every_dof_mismatch"] = every_mismatch;
    const auto sc = summarize(cut);
    state.counters["cut_med_ms"] = 1e3 * sc.median;
    state.counters["frames_changed"] = changed;
    state.counters["err_aug"] = err_aug;
    state.counters["err_refactor"] = err_ref;
    state.counters["err_updown"] = err_upd;
    state.counters["err_cg"] = err_cg;
    state.counters["cg_residual_max"] = worst_cg_res;
    state.counters["cg_iter_mean"] = changed > 0 ? static_cast<double>(cg_iterations) / changed : 0;
    state.counters["cg_iter_max"] = static_cast<double>(cg_iter_max);
    state.counters["updown_refactors"] = updown_refactors;
    state.counters["updown_failures"] = updown_failures;
    state.counters["updown_rank_max"] = rank_max;
    state.counters["updown_touched_max"] = touched_max;
    state.counters["updown_rank_mean"] = changed > 0 ? rank_sum / changed : 0;
    state.counters["updown_split_mean_ms"] = changed > 0 ? 1e3 * split_sum / changed : 0;
    state.counters["updown_cholmod_mean_ms"] = changed > 0 ? 1e3 * updown_sum / changed : 0;
    state.counters["n_final"] = static_cast<double>(prev.k.rows());
    state.counters["n0"] = n0;
  }
}
// Shipped liver at 1, 3 and 10 mm per frame (100 frames), and the refined liver at 3 mm.
BENCHMARK(BM_LiverStrategies)
    ->Args({0, 10, 100, 0})
    ->Args({0, 30, 100, 0})
    ->Args({0, 100, 100, 0})
    ->Args({0, 10, 100, 1})
    ->Args({0, 30, 100, 1})
    ->Args({0, 100, 100, 1})
    ->Args({1, 30, 100, 0})
    ->Iterations(1)
    ->Unit(benchmark::kSecond);

}  // namespace

INCISE_BENCHMARK_MAIN();

// The synchronous refactorization's elimination order (issue 17, docs/augmented.md "Synchronous
// refactorization"): the shipped liver's K after `frames` frames of the 10 mm path (no background
// jobs, so the same K every run), factored supernodally with METIS, AMD and the factor in use's
// ordering extended to the new DOFs (AugmentedSystem::extended_ordering, the default), in turn,
// `rounds` times. Counters: thread CPU of the symbolic analysis, numeric factorization and LDLᵀ
// export (median over the rounds, ms), nnz(L) and CHOLMOD's flop count.
void BM_SynchronousOrdering(benchmark::State& state) {
  const int frames = static_cast<int>(state.range(0)), rounds = static_cast<int>(state.range(1));
  const incise::mesh::MeshData& body = liver(false);
  const incise::fixtures::OrganPath path = incise::fixtures::organ_path(body);
  incise::interactive::AugmentedCutOptions opt;
  opt.automatic_refactorization = false;
  incise::interactive::AugmentedCutSession session(body, incise::fixtures::organ_material(),
                                                   path.fixed, path.forces, opt);
  for (int f = 0; f < frames; ++f) (void)session.frame(path.frame(f, 1e-2));
  incise::linalg::SparseMatrix k = session.system().current_matrix();
  k.makeCompressed();
  const std::vector<int> extended = session.system().extended_ordering(k);
  const char* names[3] = {"metis", "amd", "extended"};
  for (auto _ : state) {
    std::vector<double> t[3][3];
    for (int rep = 0; rep < rounds; ++rep) {
      for (int o = 0; o < 3; ++o) {
        incise::linalg::CholmodOptions co;
        co.kind = incise::linalg::CholmodKind::kSupernodal;
        co.ordering = o == 1 ? incise::linalg::CholmodOrdering::kAmd
                             : incise::linalg::CholmodOrdering::kMetis;
        incise::linalg::CholmodFactor fac(co);
        const double t0 = incise::thread_cpu_seconds();
        const auto st = o == 2 ? fac.analyze(k, 1, extended) : fac.analyze(k, 1);
        const double t1 = incise::thread_cpu_seconds();
        const auto sf = fac.factorize(k);
        const double t2 = incise::thread_cpu_seconds();
        const auto ldl = fac.extract_ldl();
        const double t3 = incise::thread_cpu_seconds();
        if (st != incise::linalg::FactorStatus::kOk || sf != incise::linalg::FactorStatus::kOk ||
            !ldl) {
          state.SkipWithError("factorization failed");
          return;
        }
        t[o][0].push_back(t1 - t0);
        t[o][1].push_back(t2 - t1);
        t[o][2].push_back(t3 - t2);
        state.counters[std::string(names[o]) + "_nnz_l"] = static_cast<double>(fac.nnz_l());
        state.counters[std::string(names[o]) + "_gflop"] = 1e-9 * fac.factor_flops();
      }
    }
    for (int o = 0; o < 3; ++o) {
      state.counters[std::string(names[o]) + "_analyze_ms"] = 1e3 * summarize(t[o][0]).median;
      state.counters[std::string(names[o]) + "_factorize_ms"] = 1e3 * summarize(t[o][1]).median;
      state.counters[std::string(names[o]) + "_extract_ms"] = 1e3 * summarize(t[o][2]).median;
    }
    state.counters["n"] = static_cast<double>(k.rows());
  }
}
BENCHMARK(BM_SynchronousOrdering)->Args({8, 5})->Iterations(1)->Unit(benchmark::kSecond);
