/// Interactive cutting at organ scale (issue 17): the shipped CGAL liver (16,597 tetrahedra)
/// and the same liver refined once by mesh::refine_uniform (Bey 1995, 132,776 tetrahedra),
/// linear material, held at one end and pulled at the other (reference_data/scenes/
/// liver_pull.json's supports and load), cut by a vertical scalpel that enters through the top
/// and reaches half-way down (so no part is cut free) while it follows a circle around the
/// body's centre at 1, 3 or 10 mm per frame. One frame = one blade advance = two sweep
/// triangles (AugmentedCutSession::step), each followed by the augmented solve. Each benchmark
/// is one run of the whole path (Iterations(1)); the counters are per-frame statistics of wall
/// time: cut (Cutter::step, incl. the deformed-grid rebuild), solver update (column replacements
/// + augmented solve + deformed positions) and frame = their sum; median, p95, max. Frame rate
/// target: median ≤ 33 ms, max ≤ 100 ms. The machine is shared: compare ratios within one run.
///
/// Args: refined (0/1), blade advance per frame (0.1 mm units), frames, refactor_at_m.

#include <benchmark/benchmark.h>
#include <incise/interactive/augmented_cut_session.hpp>
#include <incise/io/read_mesh.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/quality.hpp>
#include <incise/mesh/refine_uniform.hpp>
#include <incise_bench/context.hpp>

#include <algorithm>
#include <cmath>
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

/// Median, 95th percentile (nearest rank) and maximum of `v` (empty: zeros).
struct Stats {
  double median = 0, p95 = 0, max = 0;
};
Stats stats(std::vector<double> v) {
  Stats s;
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  const auto rank = [&](double q) {
    const auto k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
    return v[std::min(v.size() - 1, k == 0 ? 0 : k - 1)];
  };
  s.median = rank(0.5);
  s.p95 = rank(0.95);
  s.max = v.back();
  return s;
}

void BM_LiverScalpelPath(benchmark::State& state) {
  const bool refined = state.range(0) != 0;
  const double advance = 1e-4 * static_cast<double>(state.range(1));  // m per frame
  const int frames = static_cast<int>(state.range(2));
  const incise::mesh::MeshData& body = liver(refined);
  const auto box = incise::mesh::bounding_box(body.points);
  std::vector<Index> fixed;
  std::vector<Index> pulled;
  for (Index v = 0; v < body.num_points(); ++v) {
    if (body.points(0, v) < 0.06) fixed.push_back(v);
    if (body.points(0, v) > 0.22) pulled.push_back(v);
  }
  Eigen::Matrix3Xd forces = Eigen::Matrix3Xd::Zero(3, body.num_points());
  for (Index v : pulled) forces(0, v) = 0.5 / static_cast<double>(pulled.size());
  const incise::material::Material material("linear", {3000.0, 0.45, 0.0, 1000.0});
  incise::interactive::AugmentedCutOptions opt;
  opt.refactor_at_m = static_cast<int>(state.range(3));
  const Vec3 lo = box[0], hi = box[1];
  const Vec3 centre = 0.5 * (lo + hi);
  const double radius = 0.25 * std::min(hi.x() - lo.x(), hi.y() - lo.y());
  const double z_top = hi.z() + 0.005, z_tip = centre.z();
  for (auto _ : state) {
    incise::interactive::AugmentedCutSession session(body, material, fixed, forces, opt);
    if (!session.initial_report().ok()) {
      state.SkipWithError(session.initial_report().message.c_str());
      return;
    }
    std::vector<double> cut, update, frame;
    int failed = 0, swaps = 0, m_max = 0, iterations = 0;
    auto at = [&](double arc, double z) {
      const double phi = arc / radius;
      return Vec3(centre.x() + radius * std::cos(phi), centre.y() + radius * std::sin(phi), z);
    };
    for (int f = 0; f < frames; ++f) {
      const double s0 = advance * f, s1 = advance * (f + 1);
      const Vec3 a = at(s0, z_top), b = at(s0, z_tip), a2 = at(s1, z_top), b2 = at(s1, z_tip);
      double c = 0, u = 0;
      for (int k = 0; k < 2; ++k) {
        const incise::interactive::AugmentedCutStepReport r =
            k == 0 ? session.step(a, b, b2) : session.step(a, b2, a2);
        c += r.seconds_cut;
        u += r.seconds_update + r.seconds_solve;
        failed += r.ok() ? 0 : 1;
        swaps += r.refactorization_swapped ? 1 : 0;
        m_max = std::max(m_max, r.m_after_solve);
        iterations += r.solve.gmres.iterations;
      }
      cut.push_back(c);
      update.push_back(u);
      frame.push_back(c + u);
    }
    const Stats sc = stats(cut), su = stats(update), sf = stats(frame);
    state.counters["tets"] = static_cast<double>(body.num_cells());
    state.counters["frames"] = frames;
    state.counters["cut_med_ms"] = 1e3 * sc.median;
    state.counters["cut_p95_ms"] = 1e3 * sc.p95;
    state.counters["cut_max_ms"] = 1e3 * sc.max;
    state.counters["upd_med_ms"] = 1e3 * su.median;
    state.counters["upd_p95_ms"] = 1e3 * su.p95;
    state.counters["upd_max_ms"] = 1e3 * su.max;
    state.counters["frame_med_ms"] = 1e3 * sf.median;
    state.counters["frame_p95_ms"] = 1e3 * sf.p95;
    state.counters["frame_max_ms"] = 1e3 * sf.max;
    state.counters["m_max"] = m_max;
    state.counters["swaps"] = swaps;
    state.counters["gmres_per_frame"] = static_cast<double>(iterations) / frames;
    state.counters["failed_steps"] = failed;
    state.counters["grid_builds"] = static_cast<double>(session.cutter().grid_builds());
  }
}

// Coarse liver: 1, 3, 10 mm per frame, 100 frames, the session's defaults (refactor_at_m = 0).
BENCHMARK(BM_LiverScalpelPath)
    ->Args({0, 10, 100, 0})
    ->Args({0, 30, 100, 0})
    ->Args({0, 100, 100, 0})
    ->Args({1, 30, 100, 0})
    ->Iterations(1)
    ->Unit(benchmark::kSecond);

}  // namespace

INCISE_BENCHMARK_MAIN();
