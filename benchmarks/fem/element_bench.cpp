// Element-kernel and global-assembly benchmarks (issue 3), for every registered material:
// - Element/<model>/force, /force+product, /force+tangent: the tet kernels of
//   fem/tet_kernels.hpp over a batch of 1024 random elements (precomputed Z⁻¹ and B, as in
//   ElasticProblem), single thread, one element per call (scalar double);
// - ElementSimd4/<model>/...: the same kernels instantiated with incise::Lanes4, four elements
//   per call (what ElasticProblem uses);
// - Assembly/<model>: ElasticProblem::assemble_tangent into the fixed pattern on a 48,000-tet
//   box (tangent kernels + scatter map);
// - MatrixFree/<model>: ElasticProblem::hessian_product (K(u)·d) on the same box;
// - Gradient/<model>: ElasticProblem::gradient on the same box.
// The global loops run on one thread here (set_threads(1)); fem_threads_bench measures T threads.
// Counters: tets_per_s, counted MFLOP/s (element counts from the counting scalar × tets/s),
// % of the vector-add baseline measured in this run (thesis Table 4.5) and % of the nominal FMA
// peak of one core.
#include <benchmark/benchmark.h>
#include <incise/fem/elastic_problem.hpp>
#include <incise/fixtures/deformations.hpp>
#include <incise/mesh/generators.hpp>
#include <incise_bench/context.hpp>

#include <random>
#include <string>
#include <vector>

namespace {

using namespace incise;
using Mat34 = Eigen::Matrix<double, 3, 4>;
using Mat12 = Eigen::Matrix<double, 12, 12>;

material::Parameters bench_parameters() {
  material::Parameters p;
  p.youngs_modulus = 1.0e4;
  p.poisson_ratio = 0.4;
  p.gamma = 1.0;
  p.density = 1.0e3;
  return p;
}

/// Counters shared by every benchmark: tets/s, counted MFLOP/s, % of baselines.
void set_counters(benchmark::State& state, std::int64_t tets_per_iteration,
                  std::uint64_t flops_per_tet) {
  const double tets =
      static_cast<double>(state.iterations()) * static_cast<double>(tets_per_iteration);
  const double flops = tets * static_cast<double>(flops_per_tet);
  state.SetItemsProcessed(static_cast<std::int64_t>(tets));
  state.counters["tets_per_s"] = benchmark::Counter(tets, benchmark::Counter::kIsRate);
  state.counters["MFLOP_per_s"] = benchmark::Counter(flops * 1e-6, benchmark::Counter::kIsRate);
  state.counters["flops_per_tet"] = static_cast<double>(flops_per_tet);
  const double base = bench::vector_add_mflops();
  if (base > 0.0)
    state.counters["pct_vector_add"] =
        benchmark::Counter(flops * 1e-6 / base * 100.0, benchmark::Counter::kIsRate);
  const double peak = bench::fma_peak_mflops();
  if (peak > 0.0)
    state.counters["pct_fma_peak"] =
        benchmark::Counter(flops * 1e-6 / peak * 100.0, benchmark::Counter::kIsRate);
}

/// Elements per batch: 1024 elements' data (≈350 kB with outputs) stay in L2, so the element
/// benchmarks measure the kernels; Gradient/MatrixFree/Assembly measure the streaming case.
constexpr std::size_t kBatch = 1024;

/// A batch of random, positively oriented elements with moderate random deformations.
struct Batch {
  std::vector<fem::TetReference> refs;
  std::vector<Mat34> x;
  std::vector<Mat34> d;
  // The same elements four at a time in SIMD lanes (as ElasticProblem stores them).
  std::vector<fem::Mat3T<Lanes4>> z_inv4, b4;
  std::vector<Lanes4> volume4;
  std::vector<fem::Mat34T<Lanes4>> x4, d4;
};

const Batch& batch() {
  static const Batch b = [] {
    Batch out;
    fixtures::Rng rng(4242);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    while (out.refs.size() < kBatch) {
      const fem::TetReference r =
          fem::make_tet_reference(fixtures::random_tetrahedron(rng, 0.2, 0.05));
      Mat34 x, d;
      for (int i = 0; i < 12; ++i) {
        x(i) = 0.05 * u(rng);
        d(i) = u(rng);
      }
      out.refs.push_back(r);
      out.x.push_back(x);
      out.d.push_back(d);
    }
    for (std::size_t k = 0; k < kBatch / 4; ++k) {
      fem::Mat3T<Lanes4> zi, bt;
      fem::Mat34T<Lanes4> x, d;
      Lanes4 v;
      for (int l = 0; l < 4; ++l) {
        const std::size_t e = 4 * k + static_cast<std::size_t>(l);
        for (int i = 0; i < 9; ++i) {
          zi(i).set(l, out.refs[e].z_inv(i));
          bt(i).set(l, out.refs[e].b(i));
        }
        for (int i = 0; i < 12; ++i) {
          x(i).set(l, out.x[e](i));
          d(i).set(l, out.d[e](i));
        }
        v.set(l, out.refs[e].volume);
      }
      out.z_inv4.push_back(zi);
      out.b4.push_back(bt);
      out.volume4.push_back(v);
      out.x4.push_back(x);
      out.d4.push_back(d);
    }
    return out;
  }();
  return b;
}

enum class Kernel { kForce, kForceProduct, kForceTangent };

void element_benchmark(benchmark::State& state, const std::string& name, Kernel kernel) {
  const material::Material m(name, bench_parameters());
  const fem::ElementFlops fl = fem::element_flops(m);
  const Batch& b = batch();
  const material::Lame p = m.lame();
  const std::size_t n = b.refs.size();
  std::vector<Mat34> q(n), dq(n);
  Mat12 k;
  material::visit_model(m.model_index(), [&](auto model) {
    using K = fem::TetKernel<decltype(model), double>;
    for (auto _ : state) {
      for (std::size_t e = 0; e < n; ++e) {
        const fem::TetReference& r = b.refs[e];
        bool ok = false;
        switch (kernel) {
          case Kernel::kForce: ok = K::forces(p, r.z_inv, r.b, b.x[e], q[e]); break;
          case Kernel::kForceProduct:
            ok = K::forces_and_product(p, r.z_inv, r.b, b.x[e], b.d[e], q[e], dq[e]);
            break;
          case Kernel::kForceTangent:
            ok = K::forces_and_tangent(p, r.z_inv, r.b, r.volume, b.x[e], q[e], k);
            benchmark::DoNotOptimize(k.data());
            break;
        }
        benchmark::DoNotOptimize(ok);
      }
      benchmark::ClobberMemory();
    }
    return 0;
  });
  const std::uint64_t per = kernel == Kernel::kForce          ? fl.force
                            : kernel == Kernel::kForceProduct ? fl.force_and_product
                                                              : fl.force_and_tangent;
  set_counters(state, static_cast<std::int64_t>(n), per);
}

/// The same kernels instantiated with Lanes4: four elements per call (SoA data, no gather).
void element_benchmark_simd(benchmark::State& state, const std::string& name, Kernel kernel) {
  const material::Material m(name, bench_parameters());
  const fem::ElementFlops fl = fem::element_flops(m);
  const Batch& b = batch();
  const material::Lame p = m.lame();
  const std::size_t nb = b.x4.size();
  std::vector<fem::Mat34T<Lanes4>> q(nb), dq(nb);
  fem::Mat12T<Lanes4> k;
  material::visit_model(m.model_index(), [&](auto model) {
    using K = fem::TetKernel<decltype(model), Lanes4>;
    for (auto _ : state) {
      for (std::size_t e = 0; e < nb; ++e) {
        bool ok = false;
        switch (kernel) {
          case Kernel::kForce: ok = K::forces(p, b.z_inv4[e], b.b4[e], b.x4[e], q[e]); break;
          case Kernel::kForceProduct:
            ok = K::forces_and_product(p, b.z_inv4[e], b.b4[e], b.x4[e], b.d4[e], q[e], dq[e]);
            break;
          case Kernel::kForceTangent:
            ok = K::forces_and_tangent(p, b.z_inv4[e], b.b4[e], b.volume4[e], b.x4[e], q[e], k);
            benchmark::DoNotOptimize(k.data());
            break;
        }
        benchmark::DoNotOptimize(ok);
      }
      benchmark::ClobberMemory();
    }
    return 0;
  });
  const std::uint64_t per = kernel == Kernel::kForce          ? fl.force
                            : kernel == Kernel::kForceProduct ? fl.force_and_product
                                                              : fl.force_and_tangent;
  set_counters(state, static_cast<std::int64_t>(4 * nb), per);
}

const mesh::MeshData& box() {
  static const mesh::MeshData m = mesh::make_box(20, 20, 20, 1.0, 1.0, 1.0);  // 48,000 tets
  return m;
}

VecX box_state(const fem::ElasticProblem& pb) {
  fixtures::Rng rng(7);
  return fixtures::random_vector(rng, pb.size(), 0.002);  // 4% of a cell
}

void assembly_benchmark(benchmark::State& state, const std::string& name) {
  fem::ElasticProblem pb(box(), material::Material(name, bench_parameters()));
  pb.set_threads(1);  // one core; threads: fem_threads_bench
  const VecX u = box_state(pb);
  if (pb.assemble_tangent(u) != EvalStatus::kOk) state.SkipWithError("inverted state");
  for (auto _ : state) {
    const EvalStatus s = pb.assemble_tangent(u, fem::FixedDofTreatment::kKeep);
    benchmark::DoNotOptimize(s);
    benchmark::DoNotOptimize(pb.tangent_matrix().valuePtr());
  }
  set_counters(state, pb.num_elements(), pb.element_flop_counts().tangent + 144);
  state.counters["nnz"] = static_cast<double>(pb.tangent_matrix().nonZeros());
}

void matrix_free_benchmark(benchmark::State& state, const std::string& name) {
  fem::ElasticProblem pb(box(), material::Material(name, bench_parameters()));
  pb.set_threads(1);  // one core; threads: fem_threads_bench
  const VecX u = box_state(pb);
  const VecX d = VecX::Ones(pb.size());
  VecX out;
  for (auto _ : state) {
    const EvalStatus s = pb.hessian_product(u, d, out);
    benchmark::DoNotOptimize(s);
    benchmark::DoNotOptimize(out.data());
  }
  set_counters(state, pb.num_elements(), pb.element_flop_counts().product + 12);
}

void gradient_benchmark(benchmark::State& state, const std::string& name) {
  fem::ElasticProblem pb(box(), material::Material(name, bench_parameters()));
  pb.set_threads(1);  // one core; threads: fem_threads_bench
  const VecX u = box_state(pb);
  VecX g;
  for (auto _ : state) {
    const EvalStatus s = pb.gradient(u, g);
    benchmark::DoNotOptimize(s);
    benchmark::DoNotOptimize(g.data());
  }
  set_counters(state, pb.num_elements(), pb.element_flop_counts().force + 12);
}

/// Assembled K·d on the same box (sparse matrix-vector product), for comparison with the
/// matrix-free product.
void assembled_product_benchmark(benchmark::State& state) {
  fem::ElasticProblem pb(box(), material::Material("neohookean", bench_parameters()));
  pb.set_threads(1);
  const VecX u = box_state(pb);
  if (pb.assemble_tangent(u) != EvalStatus::kOk) state.SkipWithError("inverted state");
  const VecX d = VecX::Ones(pb.size());
  VecX out(pb.size());
  for (auto _ : state) {
    out.noalias() = pb.tangent_matrix() * d;
    benchmark::DoNotOptimize(out.data());
  }
  const double nnz = static_cast<double>(pb.tangent_matrix().nonZeros());
  state.counters["MFLOP_per_s"] = benchmark::Counter(
      2.0 * nnz * static_cast<double>(state.iterations()) * 1e-6, benchmark::Counter::kIsRate);
  state.counters["tets_per_s"] = benchmark::Counter(
      static_cast<double>(pb.num_elements()) * static_cast<double>(state.iterations()),
      benchmark::Counter::kIsRate);
}

// Every registered material is enrolled automatically.
const bool kRegistered = [] {
  for (const std::string& name : material::registered_material_names()) {
    benchmark::RegisterBenchmark(("Element/" + name + "/force").c_str(), element_benchmark, name,
                                 Kernel::kForce);
    benchmark::RegisterBenchmark(("Element/" + name + "/force+product").c_str(), element_benchmark,
                                 name, Kernel::kForceProduct);
    benchmark::RegisterBenchmark(("Element/" + name + "/force+tangent").c_str(), element_benchmark,
                                 name, Kernel::kForceTangent);
    benchmark::RegisterBenchmark(("ElementSimd4/" + name + "/force").c_str(),
                                 element_benchmark_simd, name, Kernel::kForce);
    benchmark::RegisterBenchmark(("ElementSimd4/" + name + "/force+product").c_str(),
                                 element_benchmark_simd, name, Kernel::kForceProduct);
    benchmark::RegisterBenchmark(("ElementSimd4/" + name + "/force+tangent").c_str(),
                                 element_benchmark_simd, name, Kernel::kForceTangent);
    benchmark::RegisterBenchmark(("Gradient/" + name).c_str(), gradient_benchmark, name)
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("MatrixFree/" + name).c_str(), matrix_free_benchmark, name)
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("Assembly/" + name).c_str(), assembly_benchmark, name)
        ->Unit(benchmark::kMillisecond);
  }
  benchmark::RegisterBenchmark("AssembledSpMV/neohookean", assembled_product_benchmark)
      ->Unit(benchmark::kMillisecond);
  return true;
}();

}  // namespace

INCISE_BENCHMARK_MAIN();
