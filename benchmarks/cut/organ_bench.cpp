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
/// the per-frame numbers go to <dir>/scalpel_<the 14 args joined by _>.csv, with the cost rule's
/// inputs of the capacitance factorization and, on swap frames, the thread CPU split of the
/// swapped-in job.
///
/// The executable's other benchmarks, each documented beside it: organ_kernels_bench.cpp (the
/// new columns of G and the capacitance LU), organ_strategies_bench.cpp (BM_LiverStrategies:
/// per-frame strategies side by side), organ_ordering_bench.cpp (BM_SynchronousOrdering); the
/// liver they share: organ_fixture.hpp.

#include "organ_fixture.hpp"

#include <benchmark/benchmark.h>
#include <incise/core/timer.hpp>
#include <incise/fixtures/organ_path.hpp>
#include <incise/interactive/augmented_cut_session.hpp>
#include <incise_bench/context.hpp>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

namespace incise::bench::organ {
namespace {

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
  const auto& [refined, advance, frames, body, path, material] = LiverPath(state);
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
  opt.refactorization_mode = refactorization_mode(state.range(5));
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
  const auto& [refined, advance, frames, body, path, material] = LiverPath(state);
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
    const auto st = summarize(tested), sd = summarize(dissected), sp = summarize(cpu_per_tested);
    put_ms_summary(state, "cpu_cut", cpu);
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

}  // namespace
}  // namespace incise::bench::organ

INCISE_BENCHMARK_MAIN();
