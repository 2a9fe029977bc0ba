#pragma once
// Private to the needle module: the augmented-solver path of NeedleInsertion3D
// (InsertionOptions3D::solve_path = SolvePath3D::kAugmented; contract in insertion3d.hpp).
//
// Yeung et al. 2016 §3.1 imposes and releases Dirichlet constraints and changes element
// stiffness without refactoring K. The needle constraints (§6.3.2: a sticking node fixed, a
// slipping node free along the shaft t only) are per DOF in the needle frame (t, n1, n2), so the
// whole body is posed in that frame: K̃ = PᵀKP with P = blockdiag(Q, …, Q), Q = the pose's frame
// (orthogonal), ã = Pᵀu, f̃ = Pᵀf. A sticking node's three DOFs and a slipping node's n1, n2 DOFs
// are Dirichlet DOFs at the needle's prescribed position; a refinement subtracts the cells it
// removed and adds the new ones (their rotated K_e) and appends three DOFs per new vertex. Base-
// fixed vertices keep an identity block (decoupled, zero force, zero solution), so DOF 3·v + c is
// vertex v's component c in every state. A change of the needle's direction (a new Q) or an
// explicit refactorization factors K̃ afresh (AugmentedSystem::initialize / refactor_now).

#include <incise/core/types.hpp>
#include <incise/fem/elastic_problem.hpp>
#include <incise/linalg/augmented_system.hpp>
#include <incise/material/material.hpp>
#include <incise/needle/insertion3d.hpp>
#include <incise/needle/needle3d.hpp>

#include <set>
#include <string>
#include <vector>

namespace incise::needle::detail {

class AugmentedNeedlePath {
 public:
  explicit AugmentedNeedlePath(const material::Material& material);

  /// Whether a factored system exists in frame `frame` (entries within 1e-12 of its Q).
  bool matches(const Mat3& frame) const;
  /// Assembles K̃ of `problem` in frame `frame` and factors it. False with `message` when the
  /// factorization fails (the path then has no system).
  bool reset(const fem::ElasticProblem& problem, const Mat3& frame, std::string& message);
  /// Brings the system to `problem`, a refinement of the one last reset or followed (same
  /// frame): cells compared as vertex sets, new vertices appended (vertex order kept).
  void follow(const fem::ElasticProblem& problem);
  /// Replaced columns that a refactorization would remove: m − |𝓓|.
  int changed_columns() const;
  /// Factors the current K̃ now (m drops to |𝓓|). False when the factorization failed (the old
  /// factor stays).
  bool refactor();
  /// Fresh factorizations so far (reset and refactor).
  int factorizations() const { return factorizations_; }

  /// One solve of (6.7) with the needle nodes' constraints at their positions in `u` and the
  /// loads f_ext + friction; then detail::conclude_solve (u, the nodes' coordinates, the rotated
  /// gradient). False with rep.status = kSolverFailed and the solver's message on failure.
  bool solve(fem::ElasticProblem& problem, const NeedlePose3D& pose,
             std::vector<NeedleNode3D>& nodes, const std::vector<double>& friction,
             const Eigen::Matrix3Xd& points, VecX& u, VecX& gradient, StepReport3D& rep);

 private:
  std::vector<int> element_dofs(const mesh::CellMatrix& cells, Eigen::Index e) const;
  void add_cell(const Eigen::Matrix3Xd& points, const mesh::CellMatrix& cells, Eigen::Index e,
                double scale);

  material::Material material_;
  linalg::AugmentedSystem system_;
  bool ready_ = false;
  Mat3 frame_ = Mat3::Identity();
  mesh::CellMatrix cells_;   // the cells of the system's K̃
  std::vector<char> fixed_;  // per vertex: base-fixed (identity block)
  std::set<int> constrained_;
  int factorizations_ = 0;
};

}  // namespace incise::needle::detail
