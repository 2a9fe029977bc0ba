/// Element loops on T threads (issue 19; core/parallel.hpp, ElasticProblem): energy, gradient
/// (alone and fused with the energy), K·d, the fused gradient+energy+product, the diagonal and
/// the assembled tangent are bitwise equal (memcmp) for T = 1, 2, 3, 4, 7 on a random
/// deformation of a 4,800-tet box, for every registered material; a whole nonlinear-CG solve
/// takes identical iterates and iteration counts for every T; the thread-count parser names
/// INCISE_THREADS in its errors; the chunk schedule never lets two conflicting chunks share a
/// colour; the AVX variant of the element loops equals the baseline bitwise (ElasticProblemIsa).
/// Labelled `threads`: ci/test.sh runs it under ThreadSanitizer.

#include <incise/core/error.hpp>
#include <incise/core/parallel.hpp>
#include <incise/fem/elastic_problem.hpp>
#include <incise/fixtures/deformations.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/solver/nonlinear_cg.hpp>
#include <incise_test/material_parameters.hpp>
#include <incise_test/param_names.hpp>
#include <incise_test/seed.hpp>

#include <atomic>
#include <cstring>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using incise::EvalStatus;
using incise::Index;
using incise::VecX;
using incise::fem::ElasticProblem;
using incise::fem::FixedDofTreatment;
using incise::material::Material;

const std::vector<int> kThreadCounts = {1, 2, 3, 4, 7};

incise::material::Parameters test_parameters() {
  return incise::test::fem_test_parameters();
}

/// 10 × 10 × 8 cubes × 6 = 4,800 tetrahedra: above the one-chunk size (4,096), 19 chunks of
/// kElementChunk, several per colour.
incise::mesh::MeshData test_box() {
  return incise::mesh::make_box(10, 10, 8, 0.1, 0.1, 0.08);
}

bool same_bits(const VecX& a, const VecX& b) {
  return a.size() == b.size() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<std::size_t>(a.size())) == 0;
}

bool same_bits(double a, double b) {
  return std::memcmp(&a, &b, sizeof(double)) == 0;
}

/// Everything one problem computes at (u, d) with the thread count in force.
struct Results {
  double energy = 0, fused_energy = 0, gep_energy = 0, curvature = 0;
  VecX gradient, fused_gradient, product, gep_gradient, gep_product, diagonal, matrix;
  VecX assembled_product;  ///< by ElasticProblem::assembled_hessian (K(u) assembled once)
};

Results evaluate(ElasticProblem& p, const VecX& u, const VecX& d) {
  Results r;
  EXPECT_EQ(p.energy(u, r.energy), EvalStatus::kOk);
  EXPECT_EQ(p.gradient(u, r.gradient), EvalStatus::kOk);
  EXPECT_EQ(p.gradient(u, r.fused_gradient, &r.fused_energy), EvalStatus::kOk);
  EXPECT_EQ(p.hessian_product(u, d, r.product), EvalStatus::kOk);
  EXPECT_EQ(p.gradient_energy_product(u, d, r.gep_gradient, r.gep_energy, r.gep_product),
            EvalStatus::kOk);
  EXPECT_EQ(p.hessian_curvature(u, d, r.curvature), EvalStatus::kOk);
  EXPECT_TRUE(p.hessian_diagonal(u, r.diagonal));
  const auto assembled = p.assembled_hessian(u);
  EXPECT_TRUE(assembled);
  if (assembled) {
    EXPECT_EQ(assembled(d, r.assembled_product), EvalStatus::kOk);
  }
  EXPECT_EQ(p.assemble_tangent(u, FixedDofTreatment::kKeep), EvalStatus::kOk);
  const auto& k = p.tangent_matrix();
  r.matrix = Eigen::Map<const VecX>(k.valuePtr(), k.nonZeros());
  return r;
}

/// Every result of `r` bitwise equal to `ref`'s.
void expect_same_bits(const Results& r, const Results& ref) {
  EXPECT_TRUE(same_bits(r.energy, ref.energy));
  EXPECT_TRUE(same_bits(r.fused_energy, ref.fused_energy));
  EXPECT_TRUE(same_bits(r.gep_energy, ref.gep_energy));
  EXPECT_TRUE(same_bits(r.curvature, ref.curvature));
  EXPECT_TRUE(same_bits(r.assembled_product, ref.assembled_product));
  EXPECT_TRUE(same_bits(r.gradient, ref.gradient));
  EXPECT_TRUE(same_bits(r.fused_gradient, ref.fused_gradient));
  EXPECT_TRUE(same_bits(r.product, ref.product));
  EXPECT_TRUE(same_bits(r.gep_gradient, ref.gep_gradient));
  EXPECT_TRUE(same_bits(r.gep_product, ref.gep_product));
  EXPECT_TRUE(same_bits(r.diagonal, ref.diagonal));
  EXPECT_TRUE(same_bits(r.matrix, ref.matrix));
}

/// Holds `p` (a problem on `mesh`) at x = 0 and loads it with gravity along −y.
void hold_and_load(ElasticProblem& p, const incise::mesh::MeshData& mesh) {
  p.fix_nodes(incise::fem::nodes_on_plane(mesh, 0, 0.0));
  p.add_gravity(incise::Vec3(0.0, -9.81, 0.0));
}

/// A random deformation: the homogeneous (F − I)X plus a random nodal field of amplitude 2e-3
/// (no element inverted).
template <class Rng>
VecX random_deformation(const ElasticProblem& p, const Eigen::Matrix3d& f, Rng& rng) {
  VecX u(p.size());
  for (Index v = 0; v < p.num_nodes(); ++v)
    u.segment<3>(3 * v) = (f - Eigen::Matrix3d::Identity()) * p.points().col(v);
  return u + incise::fixtures::random_vector(rng, p.size(), 2e-3);
}

/// Every node mirrored through x = 0: every element inverted (det F = −1).
VecX mirrored(const ElasticProblem& p) {
  VecX u = VecX::Zero(p.size());
  for (Index v = 0; v < p.num_nodes(); ++v) u[3 * v] = -2.0 * p.points()(0, v);
  return u;
}

class ThreadsProperty : public ::testing::TestWithParam<std::string> {};

TEST_P(ThreadsProperty, ElementLoopsBitwiseEqualForEveryThreadCount) {
  INCISE_SEEDED_RNG(rng, 1919);
  const incise::mesh::MeshData mesh = test_box();
  ElasticProblem p(mesh, Material(GetParam(), test_parameters()));
  hold_and_load(p, mesh);
  ASSERT_GT(p.chunk_schedule().num_chunks(), p.chunk_schedule().num_colours)
      << "the test mesh must let chunks run concurrently";
  Eigen::Matrix3d f;
  f << 1.15, 0.1, -0.05, 0.08, 0.92, 0.12, -0.06, 0.04, 1.07;
  const VecX u = random_deformation(p, f, rng);
  const VecX d = incise::fixtures::random_vector(rng, p.size(), 1.0);
  p.set_threads(1);
  const Results ref = evaluate(p, u, d);
  for (const int t : kThreadCounts) {
    SCOPED_TRACE("threads " + std::to_string(t));
    p.set_threads(t);
    const Results r = evaluate(p, u, d);
    expect_same_bits(r, ref);
  }
  // The fused sweeps sum in the same order as the separate ones.
  EXPECT_TRUE(same_bits(ref.fused_energy, ref.energy));
  EXPECT_TRUE(same_bits(ref.gep_gradient, ref.gradient));
  EXPECT_TRUE(same_bits(ref.gep_product, ref.product));
}

TEST_P(ThreadsProperty, InvertedElementReportedForEveryThreadCount) {
  const incise::mesh::MeshData mesh = test_box();
  ElasticProblem p(mesh, Material(GetParam(), test_parameters()));
  const VecX u = mirrored(p);
  // The status of T = 1 (kInverted for models with a log term, e.g. neo-Hookean) for every T.
  p.set_threads(1);
  double e1 = 0.0;
  VecX g1;
  const EvalStatus s1 = p.gradient(u, g1, &e1);
  if (GetParam() == "neohookean") {
    EXPECT_EQ(s1, EvalStatus::kInverted);
  }
  for (const int t : kThreadCounts) {
    SCOPED_TRACE("threads " + std::to_string(t));
    p.set_threads(t);
    double e = 0.0;
    VecX g;
    EXPECT_EQ(p.gradient(u, g, &e), s1);
    EXPECT_TRUE(same_bits(e, e1));
    EXPECT_TRUE(same_bits(g, g1));
    EXPECT_EQ(p.energy(u, e), s1);
  }
}

INSTANTIATE_TEST_SUITE_P(AllRegistered, ThreadsProperty,
                         ::testing::ValuesIn(incise::material::registered_material_names()),
                         incise::test::material_param_name);

/// The AVX variant of the element loops (KernelIsa::kAvx: the same Lanes4 operations on 256-bit
/// registers, no FMA) gives every result bitwise equal to the baseline (SSE2) variant: energy,
/// gradients, K·d, the fused sweeps, the curvature dᵀKd, diagonal, assembled tangent and the
/// product of assembled_hessian at a random deformation, on
/// 1 and 2 threads; and the same status and bits where every element is inverted (the per-element
/// double fallback inside the AVX variant). Skipped on builds or CPUs without the AVX variant.
class ElasticProblemIsa : public ::testing::TestWithParam<std::string> {};

TEST_P(ElasticProblemIsa, AvxEqualsBaselineBitwise) {
  if (!incise::fem::kernel_isa_available(incise::fem::KernelIsa::kAvx))
    GTEST_SKIP() << "no AVX element loops in this build or on this CPU";
  INCISE_SEEDED_RNG(rng, 2019);
  const incise::mesh::MeshData mesh = test_box();
  ElasticProblem p(mesh, Material(GetParam(), test_parameters()));
  hold_and_load(p, mesh);
  Eigen::Matrix3d f;
  f << 1.12, -0.07, 0.05, 0.09, 0.95, -0.1, 0.04, 0.06, 1.1;
  const VecX u = random_deformation(p, f, rng);
  const VecX d = incise::fixtures::random_vector(rng, p.size(), 1.0);
  for (const int t : {1, 2}) {
    SCOPED_TRACE("threads " + std::to_string(t));
    p.set_threads(t);
    p.set_kernel_isa(incise::fem::KernelIsa::kBaseline);
    const Results ref = evaluate(p, u, d);
    p.set_kernel_isa(incise::fem::KernelIsa::kAvx);
    const Results r = evaluate(p, u, d);
    expect_same_bits(r, ref);
  }
  // Every element inverted: same status and bits.
  const VecX w = mirrored(p);
  double e0 = 0.0, e1 = 0.0;
  VecX g0, g1;
  p.set_kernel_isa(incise::fem::KernelIsa::kBaseline);
  const EvalStatus s0 = p.gradient(w, g0, &e0);
  p.set_kernel_isa(incise::fem::KernelIsa::kAvx);
  EXPECT_EQ(p.gradient(w, g1, &e1), s0);
  EXPECT_TRUE(same_bits(e0, e1));
  EXPECT_TRUE(same_bits(g0, g1));
}

INSTANTIATE_TEST_SUITE_P(AllRegistered, ElasticProblemIsa,
                         ::testing::ValuesIn(incise::material::registered_material_names()),
                         incise::test::material_param_name);

TEST(Threads, NonlinearCgSolveIdenticalForEveryThreadCount) {
  // Veronda-Westmann box, one face fixed, gravity sideways (the issue-19 problem class), 150
  // NCG iterations: every iterate and the energy history must match T = 1 bit for bit.
  const incise::mesh::MeshData mesh = test_box();
  incise::material::Parameters prm = test_parameters();
  prm.gamma = 1.0;
  const auto run = [&](int threads, incise::solver::SolverReport& rep) {
    ElasticProblem p(mesh, Material("veronda-westmann", prm));
    hold_and_load(p, mesh);
    p.set_threads(threads);
    incise::solver::NonlinearCgOptions o;
    o.stop.epsilon = 1e-12;  // not reached: the budget ends every run
    o.budget.max_iterations = 150;
    VecX u = VecX::Zero(p.size());
    rep = incise::solver::nonlinear_cg(p, u, o);
    return u;
  };
  incise::solver::SolverReport ref;
  const VecX u1 = run(1, ref);
  ASSERT_EQ(ref.iterations, 150) << incise::solver::to_string(ref.status);
  for (const int t : {2, 3, 7}) {
    SCOPED_TRACE("threads " + std::to_string(t));
    incise::solver::SolverReport rep;
    const VecX ut = run(t, rep);
    EXPECT_EQ(rep.iterations, ref.iterations);
    EXPECT_EQ(rep.inner_iterations, ref.inner_iterations);
    EXPECT_TRUE(same_bits(ut, u1));
    ASSERT_EQ(rep.residual_history.size(), ref.residual_history.size());
    EXPECT_EQ(std::memcmp(rep.residual_history.data(), ref.residual_history.data(),
                          sizeof(double) * ref.residual_history.size()),
              0);
    ASSERT_EQ(rep.energy_history.size(), ref.energy_history.size());
    EXPECT_EQ(std::memcmp(rep.energy_history.data(), ref.energy_history.data(),
                          sizeof(double) * ref.energy_history.size()),
              0);
  }
}

TEST(Threads, ThreadCountParserNamesTheVariable) {
  EXPECT_EQ(incise::parse_thread_count(nullptr, 6), 6);
  EXPECT_EQ(incise::parse_thread_count(nullptr, 0), 1);  // hardware_concurrency() unknown
  EXPECT_EQ(incise::parse_thread_count("3", 2), 3);
  for (const char* bad : {"0", "-1", "2x", "", "257"}) {
    SCOPED_TRACE(bad);
    try {
      (void)incise::parse_thread_count(bad, 2);
      ADD_FAILURE() << "accepted";
    } catch (const incise::ParameterError& e) {
      EXPECT_NE(std::string(e.what()).find("INCISE_THREADS"), std::string::npos) << e.what();
    }
  }
  ElasticProblem p(test_box(), Material("linear", test_parameters()));
  EXPECT_THROW(p.set_threads(0), incise::ParameterError);
  // Up to 4,096 elements the loops are one chunk (the serial order); above, chunks of 256.
  ElasticProblem small(incise::mesh::make_box(8, 8, 8, 0.1, 0.1, 0.1),
                       Material("linear", test_parameters()));
  EXPECT_EQ(small.chunk_schedule().num_chunks(), 1);
  EXPECT_EQ(p.chunk_schedule().num_chunks(),
            (4800 + incise::fem::kElementChunk - 1) / incise::fem::kElementChunk);
  EXPECT_THROW(p.set_threads(incise::kMaxThreads + 1), incise::ParameterError);
}

TEST(Threads, ScheduleSeparatesConflictingChunks) {
  // Chunk c touches resources {c, c + 1} (a chain): neighbours conflict, so colours alternate
  // and every chunk of colour 1 waits for its colour-0 neighbours.
  std::vector<Index> start = {0}, res;
  for (Index c = 0; c < 9; ++c) {
    res.push_back(c);
    res.push_back(c + 1);
    start.push_back(static_cast<Index>(res.size()));
  }
  const incise::ChunkSchedule s = incise::make_chunk_schedule(start, res, 10);
  EXPECT_EQ(s.num_colours, 2);
  for (int c = 0; c + 1 < 9; ++c) EXPECT_NE(s.colour[c], s.colour[c + 1]);
  // Running it: every chunk exactly once, never overlapping a conflicting neighbour.
  std::vector<std::atomic<int>> running(9), calls(9);
  std::atomic<bool> overlap{false};
  incise::run_chunks(s, 4, [&](int c) {
    running[c].store(1);
    if ((c > 0 && running[c - 1].load() != 0) || (c < 8 && running[c + 1].load() != 0))
      overlap.store(true);
    calls[c].fetch_add(1);
    running[c].store(0);
  });
  EXPECT_FALSE(overlap.load());
  for (int c = 0; c < 9; ++c) EXPECT_EQ(calls[c].load(), 1);
  EXPECT_THROW(incise::make_chunk_schedule({0, 2}, {0, 11}, 10), incise::UsageError);
}

TEST(Threads, RunParallelRethrowsAndStaysUsable) {
  std::atomic<int> n{0};
  EXPECT_THROW(incise::run_parallel(3,
                                    [&] {
                                      if (n.fetch_add(1) == 1) throw std::runtime_error("x");
                                    }),
               std::runtime_error);
  std::atomic<int> m{0};
  EXPECT_EQ(incise::run_parallel(3, [&] { m.fetch_add(1); }), 3);
  EXPECT_EQ(m.load(), 3);
  // Nested: the inner call runs on its caller alone.
  std::atomic<int> inner{0};
  incise::run_parallel(2, [&] { inner.fetch_add(incise::run_parallel(2, [] {})); });
  EXPECT_EQ(inner.load(), 2);
}

}  // namespace
