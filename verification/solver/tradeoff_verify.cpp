/// The trade users make (issue 4, verification item 5): tolerance ε ∈ {1e-1 … 1e-8} × mesh ×
/// solver on the Table 3.1 cantilever (linear model: CG, Jacobi-PCG, SS22 with computed Δt and
/// η = 2√λ₁): error against a reference solution (ε = 1e-11, see below) and the cost of reaching
/// each ε (iterations, counted flops, seconds). One traced run per (mesh, solver) gives every ε
/// row: the row for ε is the first iterate with ‖r‖ ≤ ε‖f_ex‖. Written as CSV next to the binary.
/// Default: mesh 16×4×4; `slow` (INCISE_TRADEOFF_ALL=1) adds 24×6×6 and 32×8×8.
#include <incise/fixtures/cantilever.hpp>

#include <incise/solver/dynamic_relaxation.hpp>
#include <incise/solver/eigen_estimates.hpp>
#include <incise/solver/energy_error.hpp>
#include <incise/solver/truncated_newton.hpp>

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>

#ifndef INCISE_TRADEOFF_OUTPUT_DIR
#define INCISE_TRADEOFF_OUTPUT_DIR "."
#endif

namespace incise::verify {
namespace {

using fixtures::CantileverSetup;

struct Sample {
  long iteration;
  double seconds;
  std::uint64_t flops;
  double residual;
  double energy_error;
  double tip;  // mean tip deflection (m)
};

TEST(Tradeoff, ToleranceVsErrorAndCost) {
  const char* all = std::getenv("INCISE_TRADEOFF_ALL");
  const std::vector<int> meshes =
      all && std::string(all) == "1" ? std::vector<int>{16, 24, 32} : std::vector<int>{16};
  const std::vector<double> tolerances = {1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8};
  std::ofstream csv(std::string(INCISE_TRADEOFF_OUTPUT_DIR) + "/cantilever_tradeoff.csv");
  csv << "mesh,nodes,solver,epsilon,iterations,mflop,seconds,energy_error,tip_rel_error\n";
  std::printf("%-9s %-8s %8s %8s %9s %9s %11s %11s\n", "mesh", "solver", "epsilon", "iters",
              "MFLOP", "seconds", "(e,e)_K", "tip rel err");
  for (int nx : meshes) {
    CantileverSetup s;
    s.nx = nx;
    s.ny = s.nz = nx / 4;
    s.density = 1.0;  // masses for dynamic relaxation only; no gravity load
    const fixtures::CantileverProblem c = fixtures::make_cantilever(s);
    const mesh::MeshData& m = c.body.mesh;
    const std::vector<Index>& tip = c.body.tip;
    fem::ElasticProblem& p = *c.problem;
    const double fex = p.external_force_norm();
    auto tip_of = [&](const VecX& u) {
      double t = 0.0;
      for (Index n : tip) t -= u[3 * n + 1];
      return t / double(tip.size());
    };
    VecX ref = VecX::Zero(p.size());
    {
      solver::LinearCgOptions o;
      o.stop.rule = solver::ResidualRule::kExternalForce;
      // §4.2 asks 1e-12 for the linear model, but a displacement rounded to double already has
      // ‖r‖ ≈ 1.3e-12‖f‖ on the 16×4×4 mesh (CantileverSceneConvergence in
      // cantilever_scene_convergence_verify.cpp), more on finer ones: the reference stops at
      // 1e-11, the tightest decade above that floor.
      o.stop.epsilon = 1e-11;
      o.preconditioner = solver::Preconditioner::kJacobi;
      // The recursive CG residual drifts from the true one; a truncated Newton polish on the
      // true gradient certifies the reference.
      (void)solver::linear_cg(p, ref, o);
      solver::TruncatedNewtonOptions t;
      t.stop = o.stop;
      t.budget.max_iterations = 20;
      const solver::SolverReport rep = solver::truncated_newton(p, ref, t);
      ASSERT_TRUE(rep.ok()) << solver::to_string(rep.status) << " at |r|/|f| "
                            << rep.residual_norm / p.external_force_norm();
    }
    const double ref_tip = tip_of(ref);

    // Dynamic parameters by computation (§4.1).
    const VecX zero = VecX::Zero(p.size());
    const solver::EigenEstimate big = solver::largest_eigenvalue(p, zero);
    const solver::EigenEstimate small = solver::smallest_eigenvalue(p, zero);
    ASSERT_TRUE(big.ok() && small.ok());

    for (const std::string name : {"CG", "PCG", "SS22"}) {
      solver::EnergyErrorTrace trace(p, ref);
      std::vector<Sample> samples;
      const solver::IterationObserver obs = [&](const solver::IterationInfo& info) {
        samples.push_back(Sample{info.iteration, info.seconds, info.flops, info.residual_norm,
                                 trace.energy_error(*info.u), tip_of(*info.u)});
      };
      VecX u = zero;
      solver::StoppingRule stop;
      stop.rule = solver::ResidualRule::kExternalForce;
      stop.epsilon = tolerances.back();
      solver::SolverReport rep;
      if (name == "SS22") {
        solver::DynamicRelaxationOptions o;
        o.time_step = 0.9 * solver::critical_time_step(big.value);
        o.damping = solver::critical_damping(small.value);
        o.stop = stop;
        o.budget.max_iterations = 500000;
        o.observer = obs;
        rep = solver::dynamic_relaxation(p, u, o);
      } else {
        solver::LinearCgOptions o;
        o.stop = stop;
        o.preconditioner =
            name == "PCG" ? solver::Preconditioner::kJacobi : solver::Preconditioner::kNone;
        o.observer = obs;
        rep = solver::linear_cg(p, u, o);
      }
      ASSERT_TRUE(rep.ok()) << name << ": " << solver::to_string(rep.status);
      double prev_err = std::numeric_limits<double>::infinity();
      long prev_it = -1;
      for (double eps : tolerances) {
        const Sample* hit = nullptr;
        for (const Sample& smp : samples)
          if (smp.residual <= eps * fex) {
            hit = &smp;
            break;
          }
        ASSERT_NE(hit, nullptr) << name << " never reached " << eps;
        const double tip_err = std::abs(hit->tip - ref_tip) / ref_tip;
        csv << nx << 'x' << nx / 4 << 'x' << nx / 4 << ',' << m.num_points() << ',' << name << ','
            << eps << ',' << hit->iteration << ',' << hit->flops * 1e-6 << ',' << hit->seconds
            << ',' << hit->energy_error << ',' << tip_err << '\n';
        std::printf("%3dx%2dx%2d %-8s %8.0e %8ld %9.2f %9.4f %11.3e %11.3e\n", nx, nx / 4, nx / 4,
                    name.c_str(), eps, hit->iteration, hit->flops * 1e-6, hit->seconds,
                    hit->energy_error, tip_err);
        // Cost rises with each tighter ε; for CG the energy error falls monotonically (CG
        // minimizes it over growing Krylov spaces, §2.4.1). SS22's error need not be monotone.
        EXPECT_GE(hit->iteration, prev_it);
        if (name != "SS22") {
          EXPECT_LE(hit->energy_error, prev_err * (1 + 1e-9));
        }
        prev_err = hit->energy_error;
        prev_it = hit->iteration;
      }
      // At ε = 1e-8 the tip deflection agrees with the reference to much better than the
      // discretization error (≥ 6 % on these meshes): 1e-5 relative.
      const Sample* last = &samples.back();
      EXPECT_LT(std::abs(last->tip - ref_tip) / ref_tip, 1e-5) << name;
    }
  }
}

}  // namespace
}  // namespace incise::verify
