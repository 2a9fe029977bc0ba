#pragma once
/// \file needle_support.hpp
/// What the needle property tests (2D and 3D problems and insertions) share: one definition.

#include <incise/core/types.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/validate.hpp>
#include <incise/needle/needle_problem.hpp>
#include <incise/solver/report.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <utility>

namespace incise::test {

/// The thesis' needle material (§6.8.1): E = 3.4e4 Pa, ν = 0.34 unless given.
inline material::Material needle_material(const std::string& name = "linear", double nu = 0.34) {
  material::Parameters p;
  p.youngs_modulus = 3.4e4;
  p.poisson_ratio = nu;
  return material::Material(name, p);
}

/// n independent normal samples of standard deviation `scale`.
inline VecX gaussian_vector(std::mt19937_64& rng, Eigen::Index n, double scale) {
  std::normal_distribution<double> g(0.0, scale);
  VecX v(n);
  for (Eigen::Index i = 0; i < n; ++i) v[i] = g(rng);
  return v;
}

/// The mesh of an insertion (needle::NeedleInsertion or NeedleInsertion3D) passes
/// mesh::validate at its current positions.
template <class Insertion>
void expect_valid_mesh(const Insertion& sim) {
  mesh::ValidateOptions vo;
  vo.positions = &sim.mesh().points();
  const auto rep = mesh::validate(sim.mesh().connectivity(), vo);
  EXPECT_TRUE(rep.ok()) << rep.summary();
}

/// The stick-slip conditions of thesis §6.3.2 at the fixed point of the rearrangements of an
/// insertion (2D or 3D), recomputed from the body's own gradient: a sticking vertex's tangential
/// force within static friction (plus the rearrangement's force margin), a slipping vertex not
/// behind its anchor (less the slide margin) with its tangential force at ± dynamic friction
/// within the solver's threshold (rule (6.9)); every needle vertex on the needle. Returns
/// {sticking, slipping} counts; `needle_force`, when given, receives the sum of the needle
/// vertices' gradient entries (the force on the needle, summed in this order).
template <class Insertion,
          class Vector = std::decay_t<decltype(std::declval<Insertion&>().pose().tangent())>>
std::pair<int, int> expect_friction_inequalities(Insertion& sim, Vector* needle_force = nullptr) {
  constexpr int kDim = Vector::RowsAtCompileTime;
  const VecX& u = sim.displacement();
  VecX g;
  EXPECT_EQ(sim.problem().gradient(u, g), EvalStatus::kOk);
  const Vector t = sim.pose().tangent();
  const std::vector<double> fd = sim.dynamic_thresholds();
  const auto& nodes = sim.needle_nodes();
  needle::NeedleProblemT<kDim> np(sim.problem(), sim.pose(), nodes, fd);
  VecX gr;
  EXPECT_EQ(np.gradient(np.to_rotated(u), gr), EvalStatus::kOk);
  const double threshold = solver::residual_threshold(sim.stopping_rule(), np.external_force_norm(),
                                                      solver::fixed_norm(np, gr), np.size());
  std::pair<int, int> counts{0, 0};
  if (needle_force != nullptr) needle_force->setZero();
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    const auto& n = nodes[k];
    const Vector gk = g.template segment<kDim>(kDim * n.vertex);
    if (needle_force != nullptr) *needle_force += gk;
    const double r = gk.dot(t);  // tangential force needle → material
    const double fs = sim.friction().static_factor * fd[k];
    const auto& margin = sim.rearrange_margins();
    if (n.state == needle::NodeState::kStick) {
      // The rearrangement tested the same quantity; the recomputed gradient differs by rounding.
      EXPECT_LE(std::abs(r), fs * (1 + 1e-9) + margin.force + 1e-12)
          << "sticking vertex " << n.vertex;
      ++counts.first;
    } else {
      EXPECT_GE(n.friction_sign * (n.coords.s - n.anchor), -margin.slide)
          << "slipping vertex " << n.vertex;
      EXPECT_LE(std::abs(r - n.friction_sign * fd[k]), threshold) << "slipping vertex " << n.vertex;
      ++counts.second;
    }
    EXPECT_GE(n.coords.s, 0.0);
    EXPECT_LE(n.coords.s, sim.pose().length);
  }
  return counts;
}

}  // namespace incise::test
