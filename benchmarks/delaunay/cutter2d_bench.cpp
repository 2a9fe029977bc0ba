// Delaunay cutting in 2D (thesis §5.2.2; issue 16 speed target): time per scalpel movement of
// Cutter2D on regular meshes of ≈ 1k, 10k and 100k triangles. Each iteration cuts a fresh copy
// (copy not timed) along a slightly wavy 15 h̄ path entering near mid-height from the left, in
// steps of 0.1 h̄: 150 movements (entry, fix-up, splits, removals, flips), the last 100 timed.
// items_per_second counts timed movements; counters give their flips, removals and splits per
// movement. BM_Cutter2DScaling times the
// 1k and 100k meshes in the same iteration and reports their per-movement ratio (target ≤ 1.5).
#include <benchmark/benchmark.h>
#include <incise/delaunay/cutter2d.hpp>
#include <incise/mesh/generators.hpp>
#include <incise_bench/context.hpp>

#include <chrono>
#include <cmath>
#include <map>

namespace {

using namespace incise;
using namespace incise::delaunay;

/// Grid n × n of unit squares (2n² triangles), Delaunay already (cocircular squares).
const Triangulation& start(int n) {
  static std::map<int, Triangulation> cache;
  auto it = cache.find(n);
  if (it == cache.end())
    it = cache.emplace(n, Triangulation(mesh::make_rectangle(n, n, n, n))).first;
  return it->second;
}

struct Counts {
  long flips = 0, removals = 0, splits = 0;
  int moves = 0;
};

/// Cuts a copy of start(n); returns the counts and the time of movements 51–150 only (s). The
/// first 50 (entry, fix-up, the first splits) are not timed: they include the one-time
/// reallocation of the copied connectivity's record arrays (a copy has no spare capacity), an
/// O(n) cost that an interactive session pays once, not per movement.
double cut(int n, Counts& c) {
  Triangulation t = start(n);
  Cutter2D cutter(t);
  const double h = cutter.mean_edge(), y = n / 2 + 0.37;  // same place in every grid
  (void)cutter.move_to(Vec2(-0.5, y));
  auto move = [&](int k, bool count) {
    const CutMove2DReport r =
        cutter.move_to(Vec2(-0.5 + 0.1 * h * k, y + 0.05 * std::sin(0.1 * k)));
    if (!count) return;
    c.flips += r.flips;
    c.removals += r.removals;
    c.splits += r.splits;
    ++c.moves;
  };
  for (int k = 1; k <= 50; ++k) move(k, false);
  const auto t0 = std::chrono::steady_clock::now();
  for (int k = 51; k <= 150; ++k) move(k, true);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void BM_Cutter2DMovement(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  start(n);
  Counts c;
  for (auto _ : state) {
    double seconds = cut(n, c);
    state.SetIterationTime(seconds);
  }
  state.SetItemsProcessed(c.moves);
  state.counters["triangles"] = 2.0 * n * n;
  state.counters["flips_per_move"] = static_cast<double>(c.flips) / c.moves;
  state.counters["removals_per_move"] = static_cast<double>(c.removals) / c.moves;
  state.counters["splits_per_move"] = static_cast<double>(c.splits) / c.moves;
}
// n = 22, 71, 224: 968, 10 082, 100 352 triangles.
BENCHMARK(BM_Cutter2DMovement)
    ->Arg(22)
    ->Arg(71)
    ->Arg(224)
    ->UseManualTime()
    ->Unit(benchmark::kMicrosecond);

void BM_Cutter2DScaling(benchmark::State& state) {
  start(22);
  start(224);
  double small = 0, large = 0;
  for (auto _ : state) {
    Counts a, b;
    const double s = cut(22, a), l = cut(224, b);
    small += s;
    large += l;
    state.SetIterationTime(s + l);
  }
  state.counters["ratio_100k_over_1k"] = large / small;
}
BENCHMARK(BM_Cutter2DScaling)->UseManualTime()->Unit(benchmark::kMillisecond);

}  // namespace

INCISE_BENCHMARK_MAIN();
