#pragma once
/// \file augmented_base.hpp
/// Private to the linalg module: AugmentedSystem::Base, the factored matrix R and S of §3.5,
/// shared by augmented_system.cpp (changes, make_base), augmented_refactor.cpp (§3.6) and
/// augmented_solve.cpp (§3.1–3.5).

#include <incise/linalg/augmented_system.hpp>
#include <incise/linalg/cholmod_factor.hpp>
#include <incise/linalg/ldl_closure_solver.hpp>

#include <Eigen/Dense>

#include <memory>
#include <string>
#include <vector>

namespace incise::linalg {

// ---------------------------------------------------------------------------------------------
// Base: the factored matrix R (= K at the time of the last (re)factorization) and S of §3.5.

struct AugmentedSystem::Base {
  SparseMatrix matrix;  // K at the snapshot (the factored matrix but for `eliminated_diag`)
  // eliminate_constrained: K_dd > 0 for the DOFs d whose rows and columns the factored matrix
  // replaces by K_dd e_d, 0 elsewhere; empty when none.
  Eigen::VectorXd eliminated_diag;
  bool eliminated(int j) const { return j < eliminated_diag.size() && eliminated_diag(j) > 0; }
  std::unique_ptr<CholmodFactor> factor;
  std::shared_ptr<const LdlFactorData> ldl;
  std::unique_ptr<ClosureLdlSolver> solver;
  Eigen::VectorXd s_diag;                             // D⁻¹ in original order
  Eigen::VectorXd spai_lower, spai_diag, spai_upper;  // S(j+1,j), S(j,j), S(j,j+1)
  FactorStatus status = FactorStatus::kNotAnalyzed;
  std::string message;
  double seconds = 0;      // wall time of make_base (factorization, LDLᵀ copy, S)
  double cpu_seconds = 0;  // CPU time of the thread that ran make_base
  FactorizationCpu times;  // its split, and the background preparation of G
  // prepare_swap: G = (R⁻¹) of this factor on g_l (sorted), computed before the swap.
  std::vector<int> g_l;
  Eigen::MatrixXd g;
};

}  // namespace incise::linalg
