#pragma once
/// \file needle_problem.hpp
/// The projected minimisation (6.7) of thesis §6.6 for a body with needle nodes, as an
/// incise::Problem, and a direct (CHOLMOD) solve of the same constrained system: in 2D on a
/// plane-stress slab (fem::PlaneStressProblem, NeedlePose), in 3D on tetrahedra
/// (fem::ElasticProblem, NeedlePose3D; §6.9) — one template, NeedleProblemT<D>.
///
/// Constraints (§6.3.2): a sticking node is fixed; a slipping node may only move parallel to
/// the shaft t. The admissible movements W are spanned, per node, by the D unit vectors (free
/// node), t (slipping node) or nothing (sticking or base-fixed node). With the orthogonal
/// block-diagonal R that rotates each needle node's displacement into needle-frame components
/// (t, n) in 2D, (t, n1, n2) in 3D (the pose's frame()) and is the identity elsewhere,
/// P_W = R·P̃·Rᵀ with P̃ the diagonal 0/1 projection that zeroes fixed components.
/// This problem is posed in the rotated unknowns ũ = Rᵀu, so P_W becomes DOF zeroing and the
/// existing solvers (linear_cg, nonlinear_cg) run (6.7) unchanged: for any ũ, the CG iterates
/// in ũ are Rᵀ times those of CG with P_W in u (R is orthogonal, so norms and inner products
/// agree), P_W∇Π is the projected gradient and (I − P_W)∇Π the reaction forces of (6.9).
///
/// Rotated DOF order: D·v + 0 is the component along t (x for non-needle nodes), D·v + 1 (and
/// D·v + 2) along n (n1, n2). Slipping nodes carry the friction force σ·F_d·t as an external load
/// (the slip boundary is a prescribed traction, §6.3). Prescribed values of fixed components
/// are not set here: the caller puts them into ũ before solving; the solvers never change them.

#include <incise/core/outcome.hpp>
#include <incise/core/problem.hpp>
#include <incise/fem/elastic_problem.hpp>
#include <incise/fem/plane_stress_problem.hpp>
#include <incise/needle/needle.hpp>
#include <incise/needle/needle3d.hpp>

#include <string>
#include <vector>

namespace incise::needle {

/// The types of the needle in D dimensions: the body problem, the pose and the needle node.
template <int D>
struct NeedleSpace;
/// 2D: plane stress (§6.3).
template <>
struct NeedleSpace<2> {
  using Base = fem::PlaneStressProblem;  ///< the slab
  using Pose = NeedlePose;               ///< needle.hpp
  using Node = NeedleNode;               ///< needle.hpp
};
/// 3D: tetrahedra (§6.9).
template <>
struct NeedleSpace<3> {
  using Base = fem::ElasticProblem;  ///< the body
  using Pose = NeedlePose3D;         ///< needle3d.hpp
  using Node = NeedleNode3D;         ///< needle3d.hpp
};

/// The constrained body problem in rotated unknowns (see file comment), D = 2 or 3.
template <int D>
class NeedleProblemT : public Problem {
 public:
  using Base = typename NeedleSpace<D>::Base;  ///< body problem
  using Pose = typename NeedleSpace<D>::Pose;  ///< needle pose
  using Node = typename NeedleSpace<D>::Node;  ///< needle node
  using VecD = Eigen::Matrix<double, D, 1>;    ///< one node's displacement
  using MatD = Eigen::Matrix<double, D, D>;    ///< one node's frame

  /// `base` (kept by reference, must outlive this) with needle nodes `nodes` on a needle with
  /// frame `pose.frame()`. `friction[k]` is the friction force magnitude (N) applied to
  /// nodes[k] when it slips, along friction_sign·t. Throws UsageError for a vertex out of range,
  /// a vertex listed twice, a needle node at a DOF fixed in `base`, a slipping node with
  /// friction_sign ∉ {−1, +1}, or friction of the wrong size.
  NeedleProblemT(Base& base, const Pose& pose, const std::vector<Node>& nodes,
                 const std::vector<double>& friction);

  /// ũ = Rᵀu (both of length size()).
  VecX to_rotated(const VecX& u) const;
  /// u = Rũ.
  VecX to_original(const VecX& rotated) const;
  /// v ← P_W v in the original frame (R P̃ Rᵀ v), the projection of (6.7).
  void project_original(VecX& v) const;
  /// The friction loads in the original frame (N), length size().
  const VecX& friction_force() const { return f_fric_; }
  /// R as a sparse matrix (size() × size()).
  Eigen::SparseMatrix<double> rotation() const;
  /// The body problem this constrains.
  Base& base() const { return base_; }

  // --- incise::Problem (in rotated unknowns) --------------------------------------------
  Eigen::Index size() const override { return base_.size(); }
  [[nodiscard]] EvalStatus energy(const VecX& u, double& energy) override;
  /// Repeated at the last successful call's argument (bitwise), answered from that call.
  [[nodiscard]] EvalStatus gradient(const VecX& u, VecX& g, double* energy = nullptr) override;
  [[nodiscard]] EvalStatus hessian_product(const VecX& u, const VecX& d, VecX& out) override;
  /// A positive diagonal for Jacobi preconditioning (linear CG, solver::Preconditioner::
  /// kJacobi): the body's diag K(u) (base hessian_diagonal at R·u) at the other DOFs; at a
  /// needle node, component c gets Σ_i R_ic²·K_ii, the diagonal of RᵀKR without the node
  /// block's off-diagonal terms (still positive: any positive diagonal is a valid preconditioner,
  /// the solution is unchanged); 1 at fixed components. False when the base's fails.
  bool hessian_diagonal(const VecX& u, VecX& diag) override;
  void project(VecX& v) const override;
  bool is_fixed(Eigen::Index i) const override { return fixed_[static_cast<std::size_t>(i)] != 0; }
  /// ‖P̃ Rᵀ(f_ext + f_friction)‖₂.
  double external_force_norm() const override;
  /// Base flops plus 2·D² − D per needle node and rotation.
  std::uint64_t flops() const override;

 private:
  void rotate(VecX& v, bool transpose) const;

  Base& base_;
  MatD frame_;
  std::vector<Index> needle_vertices_;
  std::vector<char> fixed_;
  std::vector<Eigen::Index> fixed_list_;  ///< the fixed components in increasing order
  VecX f_fric_;
  mutable std::uint64_t own_flops_ = 0;
  VecX x_, dx_;  ///< scratch: the arguments rotated back to the original frame
  // The last gradient() (a solver's closing check and the caller's gradient at the returned
  // solution ask for the same point): its argument, result and energy when computed.
  VecX last_u_, last_g_;
  double last_energy_ = 0.0;
  bool has_last_ = false, last_has_energy_ = false;
};

/// The 2D needle problem (§6.6).
using NeedleProblem = NeedleProblemT<2>;
/// The 3D needle problem (§6.9).
using NeedleProblem3D = NeedleProblemT<3>;

/// Status of direct_solve().
enum class DirectStatus {
  kOk,           ///< solved
  kEvalFailed,   ///< the tangent or gradient could not be evaluated (inverted / non-finite)
  kFactorFailed  ///< CHOLMOD could not factorize the free–free block (message says why)
};

/// Name of a DirectStatus.
const char* to_string(DirectStatus s);

/// Outcome of direct_solve().
struct DirectOutcome : Outcome<DirectStatus, DirectStatus::kOk, DirectStatus::kEvalFailed> {};

/// One Newton step on the free components with a CHOLMOD factorisation of the rotated tangent
/// block K̃_FF = (RᵀK(u)R)_FF: ũ_F ← ũ_F − K̃_FF⁻¹ g̃_F(ũ). For a linear material this is the
/// exact solution of the constrained system (the reference of the CG equivalence test).
template <int D>
DirectOutcome direct_solve(NeedleProblemT<D>& problem, VecX& rotated);

}  // namespace incise::needle
