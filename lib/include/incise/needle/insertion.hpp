#pragma once
/// \file insertion.hpp
/// Needle insertion into a plane-stress slab under edge bisection: the interaction loop of
/// thesis §6.7 with the stick–slip rearrangements of §6.3.2 and the projected solves of §6.6.
///
/// One step(pose) is one pass of the §6.7 loop:
///  1. move needle: every needle node keeps its (s, d_perp) (needle.hpp) relative to the new
///     pose (the warm start of the solve; §6.7);
///  2. refine: the tip's reference position (the deformed triangle containing the tip, mapped
///     back barycentrically; no refinement when the tip is outside the deformed body or maps
///     outside the reference one through an inverted triangle) is refined with
///     BisectionMesh::refine_around until the triangle there is congruent to those of the uniform
///     h_ref slab (hypotenuse ≤ √2·h_ref); the displacement of each new vertex is the mean of its
///     two parents' (exact for linear elements, so Π is unchanged) and a new vertex on a fixed line
///     is fixed;
///  3. intercept (§6.4): every mesh edge crossed by the shaft segment [base, tip] in the
///     deformed configuration makes its endpoint closest to the crossing a needle node (sticking,
///     coordinates from its current position) unless it already is one, is fixed, or lies
///     outside 0 ≤ s ≤ L; with `relocate` (§6.8.6) its d_perp is set to 0 (projected onto the
///     needle);
///  4. solve (6.7) by linear or nonlinear CG from the current state, stopped by (6.9) with
///     force scale E·d·H (H = diagonal of the reference bounding box);
///  5. rearrange (§6.3.2) until no node changes state: a sticking node whose tangential reaction
///     |g̃_t| exceeds its static threshold slips (friction sign = sign g̃_t, friction load
///     F_d·sign·t); a slipping node re-sticks at its current s when it slid against the
///     friction since its anchor, sign·(s − anchor) < 0 (zero slip stays slipping: it is the
///     same configuration as sticking with reaction F_d ≤ F_s; with friction applied as a load its
///     tangential elastic force equals F_d at equilibrium, so the thesis' "elastic force below
///     the dynamic threshold" is decided by this kinematic form); thresholds are computed
///     from the profile once per step (dynamic_thresholds()); each change is followed by another
///     solve, at most max_rearrangements times (then kRearrangementCycle). Both tests are
///     decided beyond rounding: a reaction slips only when |g̃_t| > F_s + ε_round·(force
///     scale), a slide re-sticks only when sign·(s − anchor) < −ε_round·H (§6.8.1's rounding
///     term; at first contact the thresholds are 0 — no needle face yet — and the reactions
///     of the solve are rounding noise of either sign, which otherwise decided the states:
///     docs/needle.md "Decisions beyond rounding");
///  6. release: needle nodes with s < 0 or s > L (slid off the tip or the base) become free.
/// Anchors are reset to the current s at the start of every step.

#include <incise/core/outcome.hpp>
#include <incise/fem/plane_stress_problem.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/bisection.hpp>
#include <incise/needle/friction.hpp>
#include <incise/needle/needle.hpp>
#include <incise/solver/linear_cg.hpp>
#include <incise/solver/report.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

namespace incise::needle {

/// A fixed boundary: the reference nodes with x[axis] = value (to 1e-9 m) are held at zero
/// displacement.
struct FixedLine {
  int axis = 0;        ///< 0 (x) or 1 (y)
  double value = 0.0;  ///< coordinate of the line (m)
};

/// Relaxation used for the solves of step 4.
enum class Relaxation {
  kLinearCg,    ///< solver::linear_cg (exact static solve for the linear material)
  kNonlinearCg  ///< solver::nonlinear_cg (any material)
};

/// Options of NeedleInsertion.
struct InsertionOptions {
  double h_ref = 0.1 / 64;      ///< refinement size around the tip (m), h6 by default
  double epsilon = 1e-3;        ///< ε of (6.9)
  double epsilon_round = 1e-8;  ///< ε_round of (6.9) (§6.8.1)
  Relaxation relaxation = Relaxation::kLinearCg;
  long max_iterations = 100000;  ///< CG iterations per solve
  int max_rearrangements = 100;  ///< rearrangements per step before kRearrangementCycle
  bool relocate = false;         ///< §6.8.6: project intercepted nodes onto the needle
  /// Linear CG only: kJacobi preconditions with NeedleProblemT::hessian_diagonal (the thesis
  /// runs plain CG, the default); nonlinear CG ignores it.
  solver::Preconditioner preconditioner = solver::Preconditioner::kNone;
};

/// The rounding margins of the two rearrangement tests (file comment, item 5): ε_round times
/// the (6.9) force scale and times the body's diameter H.
struct RearrangeMargins {
  double force = 0.0;  ///< N: a sticking node slips when |g̃_t| > F_s + force
  double slide = 0.0;  ///< m: a slipping node re-sticks when sign·(s − anchor) < −slide
};

/// Status of one step.
enum class StepStatus {
  kOk,                  ///< solved, no node wants to change state
  kSolverFailed,        ///< a solve did not converge (message: the solver's report)
  kRearrangementCycle,  ///< max_rearrangements passed with nodes still changing state
  kRefinementBudget,    ///< 3D: the mesh reached max_elements before refining (insertion3d.hpp)
  kNotRun               ///< nothing done yet
};

/// Name of a StepStatus.
const char* to_string(StepStatus s);

/// Report of one step() of a D-dimensional insertion (NeedleInsertion: D = 2,
/// NeedleInsertion3D: D = 3, insertion3d.hpp).
template <int D>
struct StepReportT : Outcome<StepStatus, StepStatus::kOk, StepStatus::kNotRun> {
  using VecD = Eigen::Matrix<double, D, 1>;  ///< a point or force
  int rearrangements = 0;                    ///< state changes that triggered another solve
  int solves = 0;                            ///< solves run (rearrangements + 1 when ok)
  long cg_iterations = 0;                    ///< CG iterations over all solves
  long max_cg_iterations = 0;                ///< CG iterations of the longest solve
  std::uint64_t flops = 0;  ///< counted flops of the solves (SolverReport::flops summed)
  long bisections = 0;      ///< simple bisections done by the refinement
  int intercepted = 0;      ///< nodes that became needle nodes
  int released = 0;         ///< needle nodes released (slid off)
  int sticking = 0;         ///< needle nodes sticking at the end
  int slipping = 0;         ///< needle nodes slipping at the end
  /// Force the needle exerts on the material (N), Σ over needle nodes of −∇Π_el at the node,
  /// i.e. reactions plus friction; the needle feels its negative.
  VecD needle_force = VecD::Zero();
  /// Reference point refined around (the tip mapped to the reference configuration before the
  /// solve); NaN when the tip was outside the body.
  VecD refined_at = VecD::Constant(std::numeric_limits<double>::quiet_NaN());
  solver::StopReason last_solver_status = solver::StopReason::kConverged;  ///< of the last solve
  /// Wall time (s, core Timer) of the step's parts: refinement with the field transfer and the
  /// problem rebuild; the solves; interception, thresholds, rearrangement tests and release.
  double refine_seconds = 0.0, solve_seconds = 0.0, rearrange_seconds = 0.0;
  /// 3D only (0 in 2D): needle-surface faces and their total area (m², deformed) at the end.
  int surface_faces = 0;
  double surface_area = 0.0;  ///< see surface_faces
  /// 3D augmented path only (insertion3d.hpp SolvePath3D::kAugmented): fresh factorizations of
  /// the needle-frame stiffness in this step, and the replaced columns m of its last solve.
  int factorizations = 0;
  int replaced_columns = 0;  ///< see factorizations
};

/// Report of one 2D step().
using StepReport = StepReportT<2>;

/// A plane-stress slab pierced by a rigid needle (see file comment).
class NeedleInsertion {
 public:
  /// Slab `start` (2D right-triangle mesh, e.g. mesh::make_right_triangle_slab at h_start),
  /// `material` in plane stress with thickness `thickness` (m), fixed lines, the friction
  /// profile and options. Throws ParameterError for a bad profile, thickness, h_ref, ε or a
  /// fixed line with axis ∉ {0, 1}.
  NeedleInsertion(const mesh::MeshData& start, const material::Material& material, double thickness,
                  std::vector<FixedLine> fixed, FrictionProfile friction, InsertionOptions options);
  ~NeedleInsertion();
  NeedleInsertion(const NeedleInsertion&) = delete;
  NeedleInsertion& operator=(const NeedleInsertion&) = delete;

  /// One pass of the §6.7 loop with the needle at `pose` (file comment). Throws
  /// ParameterError for an inadmissible pose.
  StepReport step(const NeedlePose& pose);
  /// Rearrange and solve again at the current pose without moving or refining (for settling
  /// at the end of an insertion, §6.8.4).
  StepReport settle();

  /// The refined mesh.
  const mesh::BisectionMesh& mesh() const { return mesh_; }
  /// The current plane-stress problem (rebuilt after every refinement).
  fem::PlaneStressProblem& problem() { return *problem_; }
  const fem::PlaneStressProblem& problem() const { return *problem_; }
  /// Nodal displacements u (original frame, 2·vertex + component), m.
  const VecX& displacement() const { return u_; }
  /// Deformed positions (2 × vertices), m.
  Eigen::Matrix2Xd deformed() const;
  /// The needle nodes.
  const std::vector<NeedleNode>& needle_nodes() const { return nodes_; }
  /// The current pose (valid after the first step).
  const NeedlePose& pose() const { return pose_; }
  /// Friction profile.
  const FrictionProfile& friction() const { return friction_; }
  /// Options.
  const InsertionOptions& options() const { return options_; }
  /// The stopping rule used for every solve ((6.9), force scale E·d·H).
  const solver::StoppingRule& stopping_rule() const { return stop_; }
  /// The rounding margins of the rearrangement tests (insertion.hpp item 5).
  const RearrangeMargins& rearrange_margins() const { return margins_; }
  /// Dynamic friction thresholds F_d (N) of this step, entry k for needle_nodes()[k]: computed
  /// from the profile at the nodes' s at the start of the step (after moving and intercepting)
  /// and held through its rearrangements, so the solves and the tests of one step use the same
  /// friction (the s of slipping nodes changes by at most the step's slip meanwhile).
  const std::vector<double>& dynamic_thresholds() const { return thresholds_; }
  /// Whether vertex v is held by a fixed line.
  bool is_fixed_vertex(Index v) const;

 private:
  void rebuild_problem();
  void refine_at_tip();
  int intercept();
  int release();
  void place_needle_nodes();
  bool solve(StepReport& rep);
  int rearrange();
  StepReport run(StepReport rep);
  void fill_counts(StepReport& rep, bool converged);
  void update_thresholds();

  mesh::BisectionMesh mesh_;
  material::Material material_;
  double thickness_;
  std::vector<FixedLine> fixed_lines_;
  FrictionProfile friction_;
  InsertionOptions options_;
  solver::StoppingRule stop_;
  RearrangeMargins margins_;  ///< item 5
  std::unique_ptr<fem::PlaneStressProblem> problem_;
  VecX u_;
  std::vector<NeedleNode> nodes_;
  NeedlePose pose_;
  bool has_pose_ = false;
  std::vector<double> thresholds_;
  Vec2 refined_at_ = Vec2::Zero();
  VecX last_gradient_;  ///< rotated gradient at the last solution (for rearrangements)
};

}  // namespace incise::needle
