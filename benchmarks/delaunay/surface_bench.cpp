// Delaunay cutting on surfaces (thesis §5.3; issue 16 speed target): time per scalpel movement
// of SurfaceCutter on the 120° cylinder patch at ≈ 1k, 10k and 100k triangles. Each iteration
// cuts a fresh copy (copy and cutter set-up not timed) straight across at v ≈ 0.43 with a
// scalpel of 3 h̄ along the normal, in steps of 0.2 h̄: 75 movements (entry, fix-up, splits,
// removals, flips), movements 26–75 (5–15 h̄ in) timed. items_per_second counts timed movements.
// BM_SurfaceCutterScaling times the 1k and 100k patches in the same iteration and reports the
// per-movement ratio (target ≤ 1.5).
#include <benchmark/benchmark.h>
#include <incise/delaunay/surface_cutter.hpp>
#include <incise_bench/context.hpp>

#include <chrono>
#include <cmath>
#include <map>

namespace {

using namespace incise;
using namespace incise::delaunay;

const Surface& patch(int n) {
  static std::map<int, Surface> cache;
  auto it = cache.find(n);
  if (it == cache.end())
    it = cache.emplace(n, Surface(make_surface(SurfaceShape::kCylinder, n))).first;
  return it->second;
}

/// Cuts a copy of patch(n); returns the time of movements 26–75 (s) and adds their flips.
double cut(int n, long& flips, int& moves) {
  Surface s = patch(n);
  SurfaceCutter cutter(s);
  const double h = cutter.mean_edge(), du = 0.2 * h / (2 * M_PI / 3);
  auto at = [&](double u) {
    Vec3 normal;
    const Vec3 p = surface_point(SurfaceShape::kCylinder, u, 0.43 + 0.05 * u, &normal);
    return ScalpelSegment{p + 1.5 * h * normal, p - 1.5 * h * normal};
  };
  const double u0 = -0.5 * h / (2 * M_PI / 3);
  for (int k = 0; k < 25; ++k) (void)cutter.move_to(at(u0 + k * du));
  const auto t0 = std::chrono::steady_clock::now();
  for (int k = 25; k < 75; ++k) {
    flips += cutter.move_to(at(u0 + k * du)).flips;
    ++moves;
  }
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void BM_SurfaceCutterMovement(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  patch(n);
  long flips = 0;
  int moves = 0;
  for (auto _ : state) state.SetIterationTime(cut(n, flips, moves));
  state.SetItemsProcessed(moves);
  state.counters["triangles"] = 2.0 * n * n;
  state.counters["flips_per_move"] = static_cast<double>(flips) / moves;
}
// n = 22, 71, 224: 968, 10 082, 100 352 triangles.
BENCHMARK(BM_SurfaceCutterMovement)
    ->Arg(22)
    ->Arg(71)
    ->Arg(224)
    ->UseManualTime()
    ->Unit(benchmark::kMicrosecond);

void BM_SurfaceCutterScaling(benchmark::State& state) {
  patch(22);
  patch(224);
  double small = 0, large = 0;
  long flips = 0;
  int moves = 0;
  for (auto _ : state) {
    const double s = cut(22, flips, moves), l = cut(224, flips, moves);
    small += s;
    large += l;
    state.SetIterationTime(s + l);
  }
  state.counters["ratio_100k_over_1k"] = large / small;
}
BENCHMARK(BM_SurfaceCutterScaling)->UseManualTime()->Unit(benchmark::kMillisecond);

}  // namespace

INCISE_BENCHMARK_MAIN();
