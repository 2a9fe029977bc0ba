// Reader throughput (MB/s and tetrahedra/s) on a ≥100k-tetrahedron mesh (issue 2, benchmarks):
// a 30×30×20 box, 6-tetrahedron split (108,000 tetrahedra, 19,220 vertices), coordinates
// jittered so that every number has ~17 significant digits like real meshing output, written
// once per process to Gmsh 4.1, Gmsh 2.2, Medit and TetGen files in /dev/shm (or /tmp).
// Each read includes every check of read_mesh.hpp (duplicates, orientation, pinched vertices).
// VTU writing is measured too. Run: build/bench/benchmarks/io/io_reader_bench
//   --benchmark_format=json

#include <benchmark/benchmark.h>
#include <incise/io/read_mesh.hpp>
#include <incise/io/write_mesh.hpp>
#include <incise/mesh/generators.hpp>
#include <incise_bench/context.hpp>

#include <unistd.h>
#include <cstdio>
#include <fstream>
#include <random>
#include <string>

namespace {

using incise::mesh::MeshData;

struct Files {
  MeshData mesh;
  std::string dir, gmsh41, gmsh22, medit, tetgen_base;
  Files() {
    mesh = incise::mesh::make_box(30, 30, 20, 0.3, 0.3, 0.2);
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> jitter(-1e-4, 1e-4);  // 1% of the 0.01 m spacing
    for (Eigen::Index i = 0; i < mesh.points.cols(); ++i)
      for (int c = 0; c < 3; ++c) mesh.points(c, i) += jitter(rng);
    dir = ::access("/dev/shm", W_OK) == 0 ? "/dev/shm/" : "/tmp/";
    const std::string stem = dir + "incise_reader_bench_" + std::to_string(::getpid());
    gmsh41 = stem + "_41.msh";
    gmsh22 = stem + "_22.msh";
    medit = stem + ".mesh";
    tetgen_base = stem + "_tg";
    incise::io::write_gmsh(gmsh41, mesh, 41);
    incise::io::write_gmsh(gmsh22, mesh, 22);
    incise::io::write_medit(medit, mesh);
    incise::io::write_tetgen(tetgen_base, mesh);
  }
  ~Files() {
    for (const auto& p : {gmsh41, gmsh22, medit, tetgen_base + ".node", tetgen_base + ".ele"})
      std::remove(p.c_str());
  }
};

const Files& files() {
  static Files f;
  return f;
}

long long file_size(const std::string& p) {
  std::ifstream in(p, std::ios::binary | std::ios::ate);
  return static_cast<long long>(in.tellg());
}

void read_benchmark(benchmark::State& state, const std::string& path, long long bytes) {
  const auto cells = files().mesh.num_cells();
  for (auto _ : state) {
    incise::io::LoadedMesh m = incise::io::read_mesh(path);
    benchmark::DoNotOptimize(m.mesh.cells.data());
    if (m.mesh.num_cells() != cells) state.SkipWithError("wrong cell count");
  }
  state.SetBytesProcessed(state.iterations() * bytes);
  state.counters["tets_per_s"] =
      benchmark::Counter(static_cast<double>(cells), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["tets"] = static_cast<double>(cells);
  state.counters["file_MB"] = static_cast<double>(bytes) / 1e6;
}

void BM_ReadGmsh41(benchmark::State& state) {
  read_benchmark(state, files().gmsh41, file_size(files().gmsh41));
}
void BM_ReadGmsh22(benchmark::State& state) {
  read_benchmark(state, files().gmsh22, file_size(files().gmsh22));
}
void BM_ReadMedit(benchmark::State& state) {
  read_benchmark(state, files().medit, file_size(files().medit));
}
void BM_ReadTetGen(benchmark::State& state) {
  const std::string& b = files().tetgen_base;
  read_benchmark(state, b + ".ele", file_size(b + ".node") + file_size(b + ".ele"));
}

void BM_WriteVtu(benchmark::State& state) {
  const std::string path =
      files().dir + "incise_reader_bench_" + std::to_string(::getpid()) + ".vtu";
  for (auto _ : state) incise::io::write_vtu(path, files().mesh);
  state.SetBytesProcessed(state.iterations() * file_size(path));
  state.counters["tets_per_s"] = benchmark::Counter(static_cast<double>(files().mesh.num_cells()),
                                                    benchmark::Counter::kIsIterationInvariantRate);
  std::remove(path.c_str());
}

BENCHMARK(BM_ReadGmsh41)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadGmsh22)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadMedit)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadTetGen)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_WriteVtu)->Unit(benchmark::kMillisecond);

}  // namespace

INCISE_BENCHMARK_MAIN();
