// Benchmarks of conforming tetrahedral bisection (mesh/tet_bisection.hpp, thesis §6.9) at
// needle-like sizes, on the 10 cm Kuhn cube of Fig. 6.14 (make_kuhn_cube(16, 0.1): 24,576
// tetrahedra) and on the shipped liver (reference_data/meshes/liver_coarse.mesh, mm scaled to m:
// 16,597 tetrahedra, ≈ 15 cm across). Per-call times are Google Benchmark's; counters give the
// simple bisections per call and the mesh size. Argument mesh:0 is the Kuhn cube, mesh:1 the
// liver. docs/tet_bisection.md quotes one run.
//   BM_Bisect*: one bisect() of a random live tetrahedron (the mesh is rebuilt, untimed, every
//     2000 calls so that it stays near its starting size);
//   BM_RefineAround*: refine_around(x, 1 mm) at a random interior point of the coarse mesh
//     (rebuilt untimed before every call): the whole graded refinement of one needle tip;
//   BM_NeedleStep*: a needle advancing 1 mm per update along a straight line, each update
//     refine_along_segment(entry, tip, 1 mm) over the whole shaft so far (what a needle tool
//     calls per update; 40 updates, then the mesh is rebuilt untimed);
//   BM_Locate*: locate() of a random point of the refined mesh's bounding box.
#include <benchmark/benchmark.h>
#include <incise/io/read_mesh.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/mesh/quality.hpp>
#include <incise/mesh/tet_bisection.hpp>
#include <incise_bench/context.hpp>

#include <memory>
#include <random>
#include <string>

namespace {

using incise::Index;
using incise::Vec3;
using incise::mesh::ElementHandle;
using incise::mesh::MeshData;
using incise::mesh::TetBisectionMesh;

constexpr double kH = 1e-3;  // m: refinement around the needle (issue: "to 1 mm")

const MeshData& kuhn() {
  static const MeshData m = incise::mesh::make_kuhn_cube(16, 0.1);
  return m;
}

const MeshData& liver() {
  static const MeshData m = [] {
    incise::io::ReadOptions o;
    o.scale = 1e-3;  // the file is in mm
    return incise::io::read_mesh(
               std::string(INCISE_SOURCE_DIR) + "/reference_data/meshes/liver_coarse.mesh", o)
        .mesh;
  }();
  return m;
}

const MeshData& mesh_of(int which) {
  return which == 0 ? kuhn() : liver();
}

/// A random point inside the mesh (rejection sampling in the bounding box).
Vec3 random_inside(const TetBisectionMesh& m, std::mt19937_64& rng) {
  const auto box = incise::mesh::bounding_box(m.points());
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (;;) {
    const Vec3 x = box[0] + (box[1] - box[0]).cwiseProduct(Vec3(u(rng), u(rng), u(rng)));
    if (m.locate(x).valid()) return x;
  }
}

ElementHandle random_element(const TetBisectionMesh& m, std::mt19937_64& rng) {
  const auto& conn = m.connectivity();
  ElementHandle e;
  do {
    e = conn.element_at(std::uniform_int_distribution<Index>(0, conn.element_capacity() - 1)(rng));
  } while (!e.valid());
  return e;
}

void BM_Bisect(benchmark::State& state) {
  const MeshData& start = mesh_of(static_cast<int>(state.range(0)));
  std::mt19937_64 rng(7);
  auto m = std::make_unique<TetBisectionMesh>(start);
  long calls = 0, simple = 0;
  for (auto _ : state) {
    if (calls % 2000 == 0 && calls > 0) {
      state.PauseTiming();
      simple += m->num_bisections();
      m = std::make_unique<TetBisectionMesh>(start);
      state.ResumeTiming();
    }
    benchmark::DoNotOptimize(m->bisect(random_element(*m, rng)));
    ++calls;
  }
  simple += m->num_bisections();
  state.counters["simple_per_call"] = static_cast<double>(simple) / static_cast<double>(calls);
  state.counters["start_tets"] = static_cast<double>(start.num_cells());
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Bisect)->Arg(0)->Arg(1)->ArgNames({"mesh"})->Unit(benchmark::kMicrosecond);

void BM_RefineAround(benchmark::State& state) {
  const MeshData& start = mesh_of(static_cast<int>(state.range(0)));
  std::mt19937_64 rng(8);
  const TetBisectionMesh pristine(start);
  long made = 0, calls = 0;
  for (auto _ : state) {
    state.PauseTiming();
    TetBisectionMesh m = pristine;
    const Vec3 x = random_inside(m, rng);
    state.ResumeTiming();
    benchmark::DoNotOptimize(m.refine_around(x, kH));
    state.PauseTiming();
    made += m.num_bisections();
    ++calls;
    state.ResumeTiming();
  }
  state.counters["simple_per_call"] = static_cast<double>(made) / static_cast<double>(calls);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RefineAround)->Arg(0)->Arg(1)->ArgNames({"mesh"})->Unit(benchmark::kMillisecond);

void BM_NeedleStep(benchmark::State& state) {
  const MeshData& start = mesh_of(static_cast<int>(state.range(0)));
  std::mt19937_64 rng(9);
  const TetBisectionMesh pristine(start);
  constexpr int kUpdates = 40;  // 4 cm of insertion at 1 mm per update
  std::unique_ptr<TetBisectionMesh> m;
  Vec3 entry, dir;
  int step = kUpdates;
  long made = 0, updates = 0;
  Index tets = 0;
  for (auto _ : state) {
    if (step == kUpdates) {
      state.PauseTiming();
      if (m) {
        made += m->num_bisections();
        tets = m->connectivity().num_elements();
      }
      m = std::make_unique<TetBisectionMesh>(pristine);
      // A straight path of 4 cm between two interior points (both ends inside the organ).
      Vec3 a, b;
      do {
        a = random_inside(*m, rng);
        b = random_inside(*m, rng);
      } while ((b - a).norm() < 0.04);
      entry = a;
      dir = (b - a).normalized();
      step = 0;
      state.ResumeTiming();
    }
    ++step;
    benchmark::DoNotOptimize(m->refine_along_segment(entry, entry + dir * (1e-3 * step), kH));
    ++updates;
  }
  if (m) made += m->num_bisections();
  state.counters["simple_per_update"] = static_cast<double>(made) / static_cast<double>(updates);
  state.counters["tets_after_4cm"] = static_cast<double>(tets);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_NeedleStep)->Arg(0)->Arg(1)->ArgNames({"mesh"})->Unit(benchmark::kMicrosecond);

void BM_Locate(benchmark::State& state) {
  const MeshData& start = mesh_of(static_cast<int>(state.range(0)));
  std::mt19937_64 rng(10);
  TetBisectionMesh m(start);
  for (int i = 0; i < 5; ++i) m.refine_around(random_inside(m, rng), kH);
  const auto box = incise::mesh::bounding_box(m.points());
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (auto _ : state) {
    const Vec3 x = box[0] + (box[1] - box[0]).cwiseProduct(Vec3(u(rng), u(rng), u(rng)));
    benchmark::DoNotOptimize(m.locate(x));
  }
  state.counters["tets"] = static_cast<double>(m.connectivity().num_elements());
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Locate)->Arg(0)->Arg(1)->ArgNames({"mesh"})->Unit(benchmark::kMicrosecond);

}  // namespace

INCISE_BENCHMARK_MAIN();
