/// \file nonlinear_cg_quadratic_test.cpp
/// (and dynamic relaxation's recurrence, DynamicRelaxationQuadratic below)
/// Nonlinear CG (§2.4.2, line searches of §4.4.2) on a quadratic Π (Problem::energy_is_quadratic:
/// linear material): the gradient recurrence g + αK·d (one K·d per iteration) against the
/// evaluating search (K·d + gradient per iteration) on a random family of linear elastic boxes
/// and loads. Not bitwise: the recurrence gradient differs from an evaluated one by round-off,
/// so the iterates differ by round-off that CG's loss of orthogonality carries on; the tests
/// bound the consequences (same converged solution within the stopping rule's own error
/// bound, iteration counts within a few, convergence certified on an evaluated gradient).
#include <incise/fem/elastic_problem.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/solver/dynamic_relaxation.hpp>
#include <incise/solver/nonlinear_cg.hpp>

#include <incise_test/seed.hpp>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

namespace incise::solver {
namespace {

/// The same problem seen without the quadratic declaration: every call forwarded, and
/// energy_is_quadratic() left at the Problem default (false), so nonlinear_cg evaluates the
/// gradient at every trial point — the search as it was before the recurrence.
class Evaluating : public Problem {
 public:
  explicit Evaluating(Problem& p) : p_(p) {}
  Eigen::Index size() const override { return p_.size(); }
  EvalStatus energy(const VecX& u, double& e) override { return p_.energy(u, e); }
  EvalStatus gradient(const VecX& u, VecX& g, double* e) override { return p_.gradient(u, g, e); }
  EvalStatus hessian_product(const VecX& u, const VecX& d, VecX& out) override {
    return p_.hessian_product(u, d, out);
  }
  EvalStatus gradient_energy_product(const VecX& u, const VecX& d, VecX& g, double& e,
                                     VecX& out) override {
    return p_.gradient_energy_product(u, d, g, e, out);
  }
  void project(VecX& v) const override { p_.project(v); }
  bool is_fixed(Eigen::Index i) const override { return p_.is_fixed(i); }
  double external_force_norm() const override { return p_.external_force_norm(); }
  const VecX& lumped_mass() const override { return p_.lumped_mass(); }
  std::uint64_t flops() const override { return p_.flops(); }

 private:
  Problem& p_;
};

/// κ(K) of the reduced stiffness (free DOFs) from a dense eigensolve (≤ 375 DOFs here).
double condition_number(fem::ElasticProblem& prob) {
  Eigen::SparseMatrix<double> k;
  EXPECT_EQ(prob.tangent(VecX::Zero(prob.size()), k, fem::FixedDofTreatment::kKeep),
            EvalStatus::kOk);
  const std::vector<Eigen::Index> free = prob.free_dofs();
  const auto nf = static_cast<Eigen::Index>(free.size());
  const Eigen::MatrixXd kd(k);
  Eigen::MatrixXd kr(nf, nf);
  for (Eigen::Index i = 0; i < nf; ++i)
    for (Eigen::Index j = 0; j < nf; ++j) kr(i, j) = kd(free[i], free[j]);
  const Eigen::VectorXd lambda = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(kr).eigenvalues();
  return lambda.maxCoeff() / lambda.minCoeff();
}

TEST(NonlinearCgQuadratic, RecurrenceMatchesEvaluatedSearch_Sec2_4_2) {
  INCISE_SEEDED_RNG(rng, 19);
  std::uniform_int_distribution<int> cells(2, 4);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  constexpr double kEpsilon = 1e-11;  // ‖r‖ ≤ ε‖f_ext‖
  for (int trial = 0; trial < 8; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    const int nx = cells(rng), ny = cells(rng), nz = cells(rng);
    const mesh::MeshData m = mesh::make_box(nx, ny, nz, 0.05 + 0.15 * unit(rng),
                                            0.05 + 0.15 * unit(rng), 0.05 + 0.15 * unit(rng));
    material::Parameters par;
    par.youngs_modulus = std::pow(10.0, 3.0 + 2.0 * unit(rng));
    par.poisson_ratio = 0.2 + 0.25 * unit(rng);
    par.density = 1000.0;
    fem::ElasticProblem prob(m, material::Material("linear", par));
    ASSERT_TRUE(prob.energy_is_quadratic());
    prob.fix_nodes(fem::nodes_on_plane(m, 0, 0.0));
    prob.add_gravity(Vec3(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5).normalized() * 9.8);
    std::uniform_int_distribution<Index> node(0, prob.num_nodes() - 1);
    for (int k = 0; k < 3; ++k)
      prob.add_point_load({node(rng), Vec3(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5)});
    Evaluating evaluating(prob);
    ASSERT_FALSE(evaluating.energy_is_quadratic());

    NonlinearCgOptions o;
    o.stop.rule = ResidualRule::kExternalForce;
    o.stop.epsilon = kEpsilon;
    o.beta = trial % 2 == 0 ? BetaRule::kPolakRibiere : BetaRule::kFletcherReeves;
    o.line_search = trial % 4 < 2 ? LineSearchKind::kSecant : LineSearchKind::kNewton;
    o.budget.max_iterations = 20000;
    VecX u_rec = VecX::Zero(prob.size()), u_eval = VecX::Zero(prob.size());
    const SolverReport rec = nonlinear_cg(prob, u_rec, o);
    const SolverReport eval = nonlinear_cg(evaluating, u_eval, o);
    ASSERT_TRUE(rec.ok()) << rec.brief();
    ASSERT_TRUE(eval.ok()) << eval.brief();

    // The recurrence path was taken: one K·d per iteration plus an evaluated gradient every 50
    // iterations and at each convergence test it passes (a handful), against two evaluations.
    EXPECT_EQ(eval.inner_iterations, 2 * eval.iterations);
    EXPECT_LE(rec.inner_iterations, rec.iterations + rec.iterations / 50 + 5);

    // Convergence certified on an evaluated gradient at the returned u.
    VecX g;
    double e = 0.0;
    ASSERT_EQ(prob.gradient(u_rec, g, &e), EvalStatus::kOk);
    prob.project(g);
    EXPECT_LE(g.norm(), rec.threshold);
    EXPECT_EQ(e, rec.energy);  // the reported energy is the evaluated one

    // Same solution within the stopping rule's own bound. With the reduced K (free DOFs),
    // ‖u − û‖ ≤ ‖r‖/λ_min and ‖û‖ ≥ ‖f‖/λ_max, so each run is within κ(K)·ε of û relative,
    // and the two within 2κε (κ from a dense eigensolve of the reduced K: ≤ 375 DOFs).
    const double kappa = condition_number(prob);
    EXPECT_LE((u_rec - u_eval).norm(), 2.0 * kappa * kEpsilon * u_eval.norm())
        << "kappa = " << kappa;
    // Π − Π(û) = ½‖u − û‖²_K: the energies agree to far below ε relative (plus summation
    // round-off of the energy sweep, ≤ 1e-12 relative for these sizes).
    EXPECT_LE(std::abs(rec.energy - eval.energy), 1e-12 * std::abs(eval.energy));
    // Iteration counts: the round-off difference moves the count by a few iterations at most
    // (both runs converge at the same rate; CG-type counts are stable to round-off).
    EXPECT_LE(std::abs(rec.iterations - eval.iterations), 2 + eval.iterations / 20)
        << rec.iterations << " vs " << eval.iterations;
  }
}

// SS22 (§2.5) on a quadratic Π: ∇Π(ū_k) = ∇Π(ū_{k−1}) + K(ū_k − ū_{k−1}), one K-product per
// step (dynamic_relaxation), against the evaluating steps on the same random family of linear
// boxes (Δt, η from estimate_dynamic_parameters). Same bounds as the nonlinear-CG test: the
// solutions within 2κ(K)ε of each other (each within κε of û), energies within 1e-12
// relative, step counts within 2 + 5 % (the damped iteration contracts every error mode
// at a fixed rate, so round-off moves the count by a step or two), convergence certified on
// an evaluated gradient, and the product count: every step but the replacements (every 50th,
// the first, and the certifications) is a product.
TEST(DynamicRelaxationQuadratic, RecurrenceMatchesEvaluatedSteps_Sec2_5) {
  INCISE_SEEDED_RNG(rng, 1905);
  std::uniform_int_distribution<int> cells(2, 3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  constexpr double kEpsilon = 1e-9;
  for (int trial = 0; trial < 4; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    const int nx = cells(rng), ny = cells(rng), nz = cells(rng);
    const mesh::MeshData m = mesh::make_box(nx, ny, nz, 0.05 + 0.15 * unit(rng),
                                            0.05 + 0.15 * unit(rng), 0.05 + 0.15 * unit(rng));
    material::Parameters par;
    par.youngs_modulus = std::pow(10.0, 3.0 + 2.0 * unit(rng));
    par.poisson_ratio = 0.2 + 0.25 * unit(rng);
    par.density = 1000.0;
    fem::ElasticProblem prob(m, material::Material("linear", par));
    prob.fix_nodes(fem::nodes_on_plane(m, 0, 0.0));
    prob.add_gravity(Vec3(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5).normalized() * 9.8);
    Evaluating evaluating(prob);
    const DynamicParameterEstimate dp = estimate_dynamic_parameters(prob, VecX::Zero(prob.size()));
    ASSERT_TRUE(dp.ok()) << dp.brief();

    DynamicRelaxationOptions o;
    o.gradient_recurrence = true;
    o.stop.rule = ResidualRule::kExternalForce;
    o.stop.epsilon = kEpsilon;
    o.time_step = dp.time_step;
    o.damping = dp.damping;
    o.budget.max_iterations = 200000;
    VecX u_rec = VecX::Zero(prob.size()), u_eval = VecX::Zero(prob.size());
    const SolverReport rec = dynamic_relaxation(prob, u_rec, o);
    const SolverReport eval = dynamic_relaxation(evaluating, u_eval, o);
    ASSERT_TRUE(rec.ok()) << rec.brief();
    ASSERT_TRUE(eval.ok()) << eval.brief();

    EXPECT_EQ(eval.inner_iterations, 0);
    EXPECT_GE(rec.inner_iterations, rec.iterations - rec.iterations / 50 - 5);

    VecX g;
    double e = 0.0;
    ASSERT_EQ(prob.gradient(u_rec, g, &e), EvalStatus::kOk);
    prob.project(g);
    EXPECT_LE(g.norm(), rec.threshold);
    EXPECT_EQ(e, rec.energy);

    const double kappa = condition_number(prob);
    EXPECT_LE((u_rec - u_eval).norm(), 2.0 * kappa * kEpsilon * u_eval.norm())
        << "kappa = " << kappa;
    EXPECT_LE(std::abs(rec.energy - eval.energy), 1e-12 * std::abs(eval.energy));
    EXPECT_LE(std::abs(rec.iterations - eval.iterations), 2 + eval.iterations / 20)
        << rec.iterations << " vs " << eval.iterations;
  }
}

}  // namespace
}  // namespace incise::solver
