#pragma once
/// \file insertion3d.hpp
/// Needle insertion into a tetrahedral body (thesis §6.9, Fig. 6.14): the §6.7 interaction loop
/// of insertion.hpp in 3D, on conforming tetrahedral bisection (mesh/tet_bisection.hpp), with
/// the needle as a surface of mesh faces (needle3d.hpp) and friction from its area.
///
/// One step(pose) is one pass of the §6.7 loop; items 5 and 6 (rearrange, release) and the
/// report are those of the 2D loop (insertion.hpp), shared code:
///  1. move needle: every needle node keeps its (s, d_perp) relative to the new pose, whose
///     frame is the old one turned by the least rotation taking the old t to the new
///     (NeedlePose3D::moved; the normal n1 of the argument is used at the first step only);
///  2. refine: the tip is located in the deformed mesh (a deformed tetrahedron containing it,
///     inverted ones included) and mapped back barycentrically to the reference configuration;
///     when that point lies in the reference body, TetBisectionMesh::refine_around(x, h_ref)
///     refines there, and refine_along_segment(x_prev, x, h_shaft) along the tip's reference
///     trace since the previous refined point (the part of the body the shaft went through for
///     a straight insertion). New vertices get the mean displacement of their two parents
///     (exact for linear elements: Π is unchanged); new vertices in a fixed box are fixed. When
///     the mesh already has max_elements tetrahedra the step stops with kRefinementBudget
///     before refining (the needle nodes are then at the new pose, nothing else changed);
///  3. intercept (§6.4 in 3D): every tetrahedron that the needle meets in the deformed
///     configuration — its axis segment [base, tip] passes through it, or one of its edges comes
///     within r of that segment — makes its four vertices needle nodes (sticking, coordinates
///     from their current positions), except vertices that already are, are fixed, or lie
///     outside 0 ≤ s ≤ L. In 2D the closest vertex of each crossed edge suffices, since the
///     needle is a line of edges there; in 3D one vertex per crossed face would leave no face
///     with three needle vertices at coarse refinement, so the needle occupies the tetrahedra it
///     crosses and the needle surface (item 4) is the boundary of their union — the jagged
///     surface of Fig. 6.14, within about one element of the shaft;
///  4. friction thresholds (once per step, as in 2D): the needle surface of the current needle
///     nodes (needle3d.hpp), each node's third of its faces' deformed area A_k and
///     F_d,k = f(s_k)·A_k/(2πr) (FrictionProfile::surface_thresholds), F_s = static_factor·F_d;
///  5. solve (6.7) on NeedleProblem3D by linear or nonlinear CG from the current state (linear
///     CG: advanced by the previous step's increment, InsertionOptions3D::extrapolate), stopped
///     by (6.9) with force scale E·H² (H = diagonal of the reference bounding box; §6.6: "for
///     3D, the term dH should be changed, for example to H²");
///  6. rearrange and release exactly as in 2D (insertion.hpp items 5 and 6).

#include <incise/core/types.hpp>
#include <incise/fem/elastic_problem.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/tet_bisection.hpp>
#include <incise/needle/friction.hpp>
#include <incise/needle/insertion.hpp>
#include <incise/needle/needle3d.hpp>

#include <memory>
#include <vector>

namespace incise::needle {

namespace detail {
class AugmentedNeedlePath;
class FactorPreconditioner;
}  // namespace detail

/// A fixed region of a 3D body: the reference vertices in the closed box [lo, hi] (widened by
/// 1e-9 m) are held at zero displacement, also those refinement creates there. A plane
/// x[axis] = value is the box with lo = hi = value on that axis and ±∞ on the others.
struct FixedBox {
  Vec3 lo = Vec3::Zero();  ///< lower corner (m)
  Vec3 hi = Vec3::Zero();  ///< upper corner (m)
};

/// How step item 5 solves (6.7).
enum class SolvePath3D {
  kRelaxation,  ///< linear or nonlinear CG (InsertionOptions::relaxation), as the thesis does
  /// "linear" material only: the augmented system of Yeung et al. 2016 (§3.1) in the needle
  /// frame — K̃ = PᵀKP, P = blockdiag(Q) with Q the pose's frame (t, n1, n2), factored once;
  /// sticking nodes' three DOFs and slipping nodes' n1, n2 DOFs imposed and released as
  /// Dirichlet constraints without refactoring, a refinement's removed and new cells as element
  /// changes and its new vertices as new DOFs. Each solve is exact (GMRES on eq. 17 to 1e-12),
  /// so the (6.9) rule is not needed. A fresh factorization when the needle turns (Q changes by
  /// more than 1e-12) and when more than refactor_at_m replaced columns (not counting the
  /// Dirichlet DOFs) have accumulated at the start of a step (docs/needle.md).
  kAugmented
};

/// Options of NeedleInsertion3D: those of the 2D loop (h_ref: longest edge (m) of the
/// tetrahedron at the tip after refinement) and the 3D ones.
struct InsertionOptions3D : InsertionOptions {
  /// Longest edge (m) along the tip's reference trace (step item 2); 0: no shaft refinement.
  double h_shaft = 2e-3;
  /// Refinement budget: no step refines a mesh with this many tetrahedra (kRefinementBudget).
  Index max_elements = 2000000;
  /// Linear-geometry material: K·d from the stiffness assembled once per refinement
  /// (fem::ElasticProblem::set_assembled_product) instead of element products — the same
  /// solves up to rounding, faster (docs/needle.md "Fig. 6.14 and speed"). Ignored otherwise.
  /// On by default (the measured winner on the liver scene; issue 21); false: the matrix-free
  /// products of §3.1.
  bool assembled_product = true;
  /// Linear CG only: before step()'s first solve, the displacement of every vertex that is
  /// neither a needle node nor fixed is advanced by its change over the previous step (carried
  /// to new vertices by the parents' mean, as u) — the warm start extrapolated. Done after
  /// interception and thresholds, so only the solver's start changes (docs/needle.md "Fig. 6.14
  /// and speed"). Nonlinear CG starts from the previous solution (an extrapolated start can
  /// invert a neo-Hookean element). Off by default: it saves 10 % of the liver insertion's CG
  /// iterations but costs 8 % on the Fig. 6.14 linear cube.
  bool extrapolate = false;
  /// Step item 5's solver (SolvePath3D). kAugmented needs the "linear" material (ParameterError
  /// otherwise); relaxation, preconditioner, ε, assembled_product and extrapolate then do not
  /// apply.
  SolvePath3D solve_path = SolvePath3D::kRelaxation;
  /// kAugmented: a step that starts with more replaced columns than this (changed columns, not
  /// Dirichlet DOFs) factors the current K̃ first, in the calling thread — a deterministic
  /// point, so that runs repeat bitwise (docs/needle.md: the measured choice). ≥ 1.
  int refactor_at_m = 600;
  /// Linear CG with the "linear" material only (ignored otherwise): CG preconditioned by a
  /// CHOLMOD factor of the needle problem's rotated stiffness K̃_FF at its last factorization
  /// (constrained DOFs decoupled), with Jacobi scaling on DOFs that refinement added since;
  /// replaces `preconditioner`. The factor is renewed at the start of a step, a deterministic
  /// point (runs repeat bitwise), when more than refactor_fraction of the DOFs were added or
  /// changed their fixed state since it was computed (docs/needle.md "Where the liver's update
  /// time goes, and the factor preconditioner": it cuts CG iterations 10–20× but costs more
  /// CPU than it saves on the liver scene). Off by default.
  bool factor_preconditioner = false;
  /// See factor_preconditioner; in [0, 1] (0: a fresh factor at every step that changed a DOF).
  double refactor_fraction = 0.02;
};

/// Report of one 3D step (insertion.hpp StepReportT).
using StepReport3D = StepReportT<3>;

/// A tetrahedral body pierced by a rigid needle of radius r (see file comment).
class NeedleInsertion3D {
 public:
  /// Body `start` (3D tetrahedra, positively oriented, reference configuration), `material`,
  /// fixed boxes, friction profile and options. Throws ParameterError for a bad profile, h_ref,
  /// h_shaft, ε, max_elements, a fixed box with a non-finite corner or lo > hi, or a mesh that
  /// is not 3D tetrahedra (as TetBisectionMesh and fem::ElasticProblem do).
  NeedleInsertion3D(const mesh::MeshData& start, const material::Material& material,
                    std::vector<FixedBox> fixed, FrictionProfile friction,
                    InsertionOptions3D options);
  ~NeedleInsertion3D();
  NeedleInsertion3D(const NeedleInsertion3D&) = delete;
  NeedleInsertion3D& operator=(const NeedleInsertion3D&) = delete;

  /// One pass of the §6.7 loop with the needle at `pose` (file comment). Throws ParameterError
  /// for an inadmissible pose.
  StepReport3D step(const NeedlePose3D& pose);
  /// Rearrange and solve again at the current pose without moving or refining.
  StepReport3D settle();
  /// Refines the body around reference point x to longest edge h (m) as step item 2 does
  /// (TetBisectionMesh::refine_around, new vertices' u the mean of their parents', the problem
  /// rebuilt); no solve. Returns the number of new vertices. Throws UsageError as
  /// refine_around (x outside the body, h not finite and > 0).
  int refine_around(const Vec3& x, double h);

  /// The refined mesh.
  const mesh::TetBisectionMesh& mesh() const { return *mesh_; }
  /// The current elastic problem (rebuilt after every refinement).
  fem::ElasticProblem& problem() { return *problem_; }
  const fem::ElasticProblem& problem() const { return *problem_; }
  /// Nodal displacements u (3·vertex + component), m.
  const VecX& displacement() const { return u_; }
  /// Deformed positions (3 × vertices), m.
  Eigen::Matrix3Xd deformed() const;
  /// The needle nodes.
  const std::vector<NeedleNode3D>& needle_nodes() const { return nodes_; }
  /// The current pose (valid after the first step).
  const NeedlePose3D& pose() const { return pose_; }
  /// The needle surface (needle3d.hpp) of the needle nodes at the end of the last step.
  const mesh::CellMatrix& needle_surface() const { return surface_; }
  /// Friction profile.
  const FrictionProfile& friction() const { return friction_; }
  /// Options.
  const InsertionOptions3D& options() const { return options_; }
  /// The stopping rule used for every solve ((6.9), force scale E·H²).
  const solver::StoppingRule& stopping_rule() const { return stop_; }
  /// The rounding margins of the rearrangement tests (insertion.hpp item 5).
  const RearrangeMargins& rearrange_margins() const { return margins_; }
  /// Dynamic friction thresholds F_d (N) of this step, entry k for needle_nodes()[k] (step
  /// item 4), held through the step's rearrangements.
  const std::vector<double>& dynamic_thresholds() const { return thresholds_; }
  /// Whether vertex v lies in a fixed box.
  bool is_fixed_vertex(Index v) const;

 private:
  void rebuild_problem();
  void refine_at_tip(StepReport3D& rep);
  int carry_field(Index before);
  int intercept();
  void place_needle_nodes();
  void update_thresholds();
  void update_surface(StepReport3D& rep);
  void extrapolate();
  StepReport3D run(StepReport3D rep);
  bool prepare_augmented(StepReport3D& rep);
  bool prepare_factor(StepReport3D& rep);

  std::unique_ptr<mesh::TetBisectionMesh> mesh_;
  material::Material material_;
  std::vector<FixedBox> fixed_;
  FrictionProfile friction_;
  InsertionOptions3D options_;
  solver::StoppingRule stop_;
  RearrangeMargins margins_;  ///< insertion.hpp item 5
  std::unique_ptr<fem::ElasticProblem> problem_;
  VecX u_;
  std::vector<NeedleNode3D> nodes_;
  NeedlePose3D pose_;
  bool has_pose_ = false;
  bool has_trace_ = false;
  Vec3 trace_ = Vec3::Zero();  ///< the last refined reference point (the tip's trace)
  std::vector<double> thresholds_;
  mesh::CellMatrix surface_ = mesh::CellMatrix(3, 0);
  VecX last_gradient_;
  bool extrapolate_now_ = false;  ///< step() sets it for run()
  VecX u_end_;      ///< u at the end of the previous step (carried through refinement)
  VecX increment_;  ///< u_end_ minus u at the end of the step before (carried likewise)
  std::unique_ptr<detail::AugmentedNeedlePath> augmented_;  ///< SolvePath3D::kAugmented
  std::unique_ptr<detail::FactorPreconditioner> factor_;    ///< factor_preconditioner
};

}  // namespace incise::needle
