#pragma once
/// \file augmented_cut_session.hpp
/// One interactive cutting session on a linear-elastic body whose static solution is kept
/// current by the augmented-matrix solver (thesis §3.2 cut steps; Yeung, Crouch & Pothen 2016
/// §3 column replacements). It owns the cut mesh, the Cutter and a linalg::AugmentedSystem.
///
/// Each frame() is one or more sweep triangles (one blade advance, rendered once): Cutter::step
/// for each, then what they changed translated into column replacements (old element blocks
/// subtracted, new ones added, new DOFs for new nodes, Dirichlet constraints for nodes fixed on a
/// face or left without elements), then one AugmentedSystem::solve(); step() is the frame of one
/// triangle. The translation table, the DOF numbering and the diagonal spring that keeps K positive
/// definite are in docs/cutting.md ("Integration with the augmented solver").
///
/// DOF numbering: nodes fixed at construction have no DOFs; the other used nodes of the initial
/// mesh get 3·k, 3·k+1, 3·k+2 in node order; new nodes get the next DOFs in creation order.
///
/// Failure is a status (CutSolveStatus), never an exception: a free component (policy kReport),
/// an element inverted in the reference configuration, or the augmented solve's own status.

#include <incise/core/outcome.hpp>
#include <incise/core/types.hpp>
#include <incise/cut/cut_mesh.hpp>
#include <incise/cut/cutter.hpp>
#include <incise/interactive/refactorization_policy.hpp>
#include <incise/linalg/augmented_system.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/mesh_data.hpp>

#include <array>
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace incise::interactive {

/// Options of an AugmentedCutSession.
struct AugmentedCutOptions {
  /// AugmentedOptions with a supernodal CHOLMOD factor and eq. 17 preconditioned by the
  /// explicit H R⁻¹ J (linalg::interactive_options(); see `augmented`).
  static linalg::AugmentedOptions supernodal_defaults() { return linalg::interactive_options(); }
  cut::CutOptions cut;  ///< the cutter's options (thesis defaults)
  /// The augmented solver's options: K⁰ factored supernodally (METIS ordering kept), eq. 17
  /// preconditioned by the explicit H R⁻¹ J in capacitance form (why, and the measurements
  /// behind the choice: docs/cutting.md, docs/augmented.md).
  linalg::AugmentedOptions augmented = supernodal_defaults();
  /// After every successful solve set the cut mesh's deformed positions to X + a, so that the
  /// next sweep triangle is interpreted in the deformed configuration (§3.2). O(n) per solve
  /// for the positions; the cutter's boundary search grid is updated, not rebuilt: only the
  /// stars of nodes that moved more than CutOptions::search_grid_slack cells are entered again;
  /// false keeps x = X (cutting in the reference configuration).
  bool update_deformed = true;
  /// §3.6 of the augmented paper (automatic background refactorization), in replaced columns
  /// (a count). After a step's (or solve()'s) augmented solve, when the replaced columns that
  /// a refactorization can remove — m − |𝓓|, m = |𝓛|; the Dirichlet DOFs 𝓓 stay in 𝓛 after
  /// any refactorization, so counting them would restart a useless job after every solve once
  /// |𝓓| reached the threshold — number at least `refactor_at_m` and no refactorization is
  /// pending, the session starts one (AugmentedSystem::start_refactorization(): the current K
  /// is factored in a background thread). The next solve() that finds it finished swaps it in,
  /// and m drops to m′ + |𝓓|, m′ the columns changed since the job started. 0 = never (m grows
  /// for the whole cut). Why (§3.6): the update cost grows with m (GMRES on the m × m Schur
  /// system, eq. 17, and the closures of its columns) while a factorization costs about the
  /// same at any m, so the paper bounds m "by periodically re-computing a full LDLᵀ
  /// factorization of K in a process that runs concurrently with the simulation loop"; a
  /// threshold near the m at which the accumulated extra update time has reached one
  /// factorization time follows its argument. The job wants a second core. Must be ≥ 0.
  /// A value > 0 overrides `automatic_refactorization`.
  int refactor_at_m = 0;
  /// With refactor_at_m = 0: start the §3.6 background refactorization when
  /// RefactorizationPolicy (refactorization_policy.hpp) says so, in `refactorization_mode`.
  /// On by default; false (and refactor_at_m = 0) never refactors.
  bool automatic_refactorization = true;
  /// The automatic policy's rule: kContinuous (default) keeps a background factorization
  /// running whenever m − |𝓓| > 0 (it wants the second core); kBreakEven starts one when the
  /// summed extra update cost reached one factorization's (the paper's single-core argument).
  /// Measured side by side on the liver path, with augmented.prepare_swap on (the default):
  /// docs/augmented.md, "Refactorization policy". Scene key `refactorization` (docs/scenes.md).
  RefactorizationMode refactorization_mode = kDefaultRefactorizationMode;
  /// Refactor every step instead of updating (the "refactor every step" strategy of
  /// docs/augmented.md, organ scale): before each solve that follows a change, the current K is
  /// factored in the calling thread and swapped in (AugmentedSystem::refactor_now(): m drops to
  /// |𝓓|), so the solve is a factorization plus a solve with m = |𝓓|. Its time is part of the
  /// step's update. Measured slower than the augmented update on the liver path at 1, 3 and
  /// 10 mm per frame, and 1.8–3.1× a bare CHOLMOD factorization + solve (it also makes the LDLᵀ
  /// copy and the capacitance data), so no scene key selects it (docs/augmented.md,
  /// "Per-frame strategies"). Overrides refactor_at_m and automatic_refactorization (no
  /// background job is started).
  bool refactor_every_step = false;
  /// §3.6 pipeline: after each solve, also poll the background job (AugmentedSystem::
  /// poll_refactorization) so that one that finished during the solve is handed to the
  /// preparation of its swap (AugmentedOptions::prepare_swap), or swapped in, now rather than at
  /// the next solve — a frame earlier with one solve per frame. On by default; measured:
  /// docs/augmented.md, "One solve per frame".
  bool poll_after_solve = true;
  /// Issue 17, with the automatic policy (automatic_refactorization, refactor_at_m = 0): before
  /// a solve, refactor the current K in the calling thread (AugmentedSystem::refactor_now with
  /// `synchronous_ordering`, pending background jobs abandoned) when SynchronousRefactorRule
  /// predicts that the augmented solve at the current m would cost more CPU than that
  /// refactorization — the measured CPU (symbolic analysis, numeric factorization, LDLᵀ copy)
  /// of the last synchronous one, before the first the factor in use's. m then drops to 0.
  /// On by default; measured: docs/augmented.md, "Synchronous refactorization (issue 17)".
  bool synchronous_refactorization = true;
  /// Elimination order of a synchronous refactorization: by default the factor in use's,
  /// extended to the DOFs added since (no ordering computed: a cheaper symbolic analysis than
  /// METIS's for somewhat more fill; measured in docs/augmented.md). Background
  /// jobs keep AugmentedOptions::cholmod's (METIS).
  linalg::RefactorOrdering synchronous_ordering = linalg::RefactorOrdering::kExtendCurrent;
  /// Predicted CPU of the next augmented solve at m with k new columns of G (AugmentedSystem::
  /// columns_without_g) for the synchronous choice; empty: SynchronousRefactorRule on the
  /// measured solves. Tests inject a deterministic model.
  std::function<double(int m, int k)> synchronous_solve_cost;
  /// CPU of a synchronous refactorization for the synchronous choice; empty: measured (see
  /// synchronous_refactorization). Tests inject a deterministic model.
  std::function<double(const linalg::AugmentedSystem&)> synchronous_refactor_cost;
  /// Cost of one solver update for the automatic policy; empty: its measured wall time
  /// (AugmentedReport::seconds_total). Tests inject a deterministic model.
  std::function<double(const linalg::AugmentedReport&)> update_cost;
  /// Cost of one factorization for the automatic policy; empty: the measured one of the factor
  /// in use (AugmentedSystem::factorization_seconds()). Tests inject a deterministic model.
  std::function<double(const linalg::AugmentedSystem&)> factorization_cost;
};

/// Outcome of the solver update of one step.
enum class CutSolveStatus {
  kOk,               ///< solved; displacement() is the static solution of the cut mesh
  kFreeComponent,    ///< a component without fixed nodes exists (policy kReport): K is
                     ///< singular, no solve was made; displacement() keeps the last solution
  kInvertedElement,  ///< a live element has non-positive reference volume: no stiffness
  kSolverFailed      ///< AugmentedSystem::solve() failed; see AugmentedCutStepReport::solve
};

/// Human-readable name of a CutSolveStatus.
const char* to_string(CutSolveStatus status);

/// Report of one interactive frame (its sweep triangles cut, then one solver update; step():
/// one triangle). message: what the caller can do when status != kOk.
struct [[nodiscard]] AugmentedCutStepReport
    : Outcome<CutSolveStatus, CutSolveStatus::kOk, CutSolveStatus::kOk> {
  /// The cutter's reports merged over the frame's triangles (one triangle: its report as is):
  /// counts summed, lists concatenated in triangle order (a node or element may appear in
  /// several; a node created by one triangle and removed by a later one is in both new_nodes
  /// and removed_nodes), faces_pending and incomplete_elements after the last triangle,
  /// full_component_check if any, status the first one that is not ok (with its message).
  cut::CutStepReport cut;
  int triangles = 0;  ///< sweep triangles cut in this frame (step(): 1; solve(): 0)
  // Translation into column replacements (this frame, after all its triangles).
  Index elements_subtracted = 0;  ///< element stiffnesses removed (old version of a slot)
  Index elements_added = 0;       ///< element stiffnesses added (new version of a slot)
  Index dofs_added = 0;           ///< new DOFs (3 per new free node)
  Index constrained_fixed = 0;    ///< DOFs constrained because the cutter fixed their node
  Index constrained_unused = 0;   ///< DOFs constrained because their node lost all elements
  Index free_components = 0;      ///< components without fixed nodes in the mesh (cumulative)
  Index inverted_elements = 0;    ///< live elements with reference volume ≤ 0 (current)
  bool solved = false;            ///< whether AugmentedSystem::solve() ran
  linalg::AugmentedReport solve;  ///< m = |𝓛|, GMRES iterations, closures, solver timings
  // §3.6 background refactorization (AugmentedCutOptions::refactor_at_m).
  int m_before_solve = 0;  ///< m = |𝓛| after this step's column replacements, before the solve
  int m_after_solve = 0;   ///< m after the solve (after a swap, if any; unchanged without one)
  /// The solve swapped in a finished background factorization (m_after_solve then counts only
  /// the columns changed since it started, plus 𝓓); solve.refactorization_status tells whether
  /// a finished job failed (it is then dropped: the old factor stays in use).
  bool refactorization_swapped = false;
  /// After the solve, m ≥ refactor_at_m with no job pending: a background refactorization of
  /// the current K was started.
  bool refactorization_started = false;
  /// Before the solve the current K was refactored in the calling thread
  /// (AugmentedCutOptions::synchronous_refactorization; refactorization_swapped says whether it
  /// succeeded); its time is part of cpu_seconds_update.
  bool synchronous_refactorization = false;
  // Timings (seconds) of the whole frame. CPU = CLOCK_THREAD_CPUTIME_ID of the calling thread.
  double seconds_cut = 0;         ///< wall time of cut::Cutter::step (summed over the triangles)
  double seconds_update = 0;      ///< wall time of the column replacements (no solve)
  double seconds_solve = 0;       ///< wall time of AugmentedSystem::solve() (+ deformed update)
  double cpu_seconds_cut = 0;     ///< CPU time of cut::Cutter::step
  double cpu_seconds_update = 0;  ///< CPU time of the column replacements and the solve
};

/// A cut mesh, its cutter and the augmented linear-elastic static solver, kept consistent
/// step by step (see file comment). Not copyable or movable (the cutter refers to the mesh);
/// hold it by std::unique_ptr when needed. Not thread-safe.
class AugmentedCutSession {
 public:
  /// Body `mesh` (3D tetrahedra, reference configuration, m) of linear material `material`
  /// ("linear" model: thesis (2.22)); nodes `fixed_nodes` are held at zero displacement;
  /// `node_forces` (3 × num_points, N) are the external nodal forces. Factors K⁰ and solves
  /// the uncut problem: the outcome is initial_report(). Throws ParameterError for a
  /// non-linear material, a non-tetrahedral mesh, a bad node index or a force matrix of the
  /// wrong size; UsageError for an invalid mesh (from CutMesh).
  AugmentedCutSession(const mesh::MeshData& mesh, const material::Material& material,
                      const std::vector<Index>& fixed_nodes, const Eigen::Matrix3Xd& node_forces,
                      AugmentedCutOptions options = {});
  ~AugmentedCutSession();
  AugmentedCutSession(const AugmentedCutSession&) = delete;
  AugmentedCutSession& operator=(const AugmentedCutSession&) = delete;

  /// Report of the initial factorization and solve (cut fields empty). When the factorization
  /// of K⁰ gives any FactorStatus but kOk (not positive definite, e.g. no fixed nodes; a
  /// CHOLMOD warning such as kTinyPivot) status is kSolverFailed with solve.status kNoFactor
  /// and a message naming the FactorStatus; steps then cut the mesh but cannot solve.
  const AugmentedCutStepReport& initial_report() const { return initial_; }

  /// One interactive frame: Cutter::step on each sweep triangle of `triangles` in order (all in
  /// the deformed configuration of the last solve, m — no solve between them, so the positions
  /// are those the user saw when the frame began), then the translation of everything they
  /// changed into column replacements, and one augmented solve (none when nothing changed and
  /// the last solution stands). Post: displacement() is the static solution of the cut mesh
  /// when ok(). count = 0 cuts nothing (a solve only if the last one is stale).
  /// Cutting per frame rather than per triangle gives a different mesh in general: the later
  /// triangles meet the nodes where the previous frame left them, not where an intermediate
  /// solve would have moved them (docs/augmented.md, "One solve per frame").
  AugmentedCutStepReport frame(const std::array<Vec3, 3>* triangles, std::size_t count);
  /// frame() on the triangles of a vector or an array (e.g. fixtures::OrganPath::frame).
  AugmentedCutStepReport frame(const std::vector<std::array<Vec3, 3>>& triangles) {
    return frame(triangles.data(), triangles.size());
  }
  template <std::size_t N>
  AugmentedCutStepReport frame(const std::array<std::array<Vec3, 3>, N>& triangles) {
    return frame(triangles.data(), N);
  }
  /// The frame of one sweep triangle (a, b, c).
  AugmentedCutStepReport step(const Vec3& a, const Vec3& b, const Vec3& c) {
    const std::array<Vec3, 3> tri{a, b, c};
    return frame(&tri, 1);
  }
  /// Same with the triangle as an array.
  AugmentedCutStepReport step(const std::array<Vec3, 3>& tri) { return frame(&tri, 1); }

  /// Ends the current incision (Cutter::end_incision): the next step starts a new one.
  void end_incision() { cutter_->end_incision(); }

  /// Changes the external force on node v (N); takes effect at the next solve.
  void set_node_force(Index v, const Vec3& force);
  /// Solves again without cutting (e.g. after set_node_force); cut fields of the report empty.
  AugmentedCutStepReport solve();

  /// §3.6 of the augmented paper: refactors the current K in a background thread; later
  /// solves swap it in and m drops. Returns false if a job is already running (unless a second
  /// may overlap it: linalg::AugmentedOptions::overlap_stale_columns). Started automatically
  /// by the policy (AugmentedCutOptions::automatic_refactorization, refactor_at_m).
  bool start_refactorization() { return system_->start_refactorization(); }
  /// Blocks until a pending background refactorization finishes and swaps it in (m drops);
  /// returns whether a factor was swapped in (false: none pending, or the job failed).
  bool wait_for_refactorization();
  /// The automatic policy's state (AugmentedCutOptions::automatic_refactorization).
  const RefactorizationPolicy& refactorization_policy() const { return policy_; }
  /// The synchronous choice's cost model (AugmentedCutOptions::synchronous_refactorization).
  const SynchronousRefactorRule& synchronous_rule() const { return sync_rule_; }
  /// Synchronous refactorizations made so far.
  int synchronous_refactorizations() const { return sync_count_; }

  /// The cut mesh (reference and deformed positions, connectivity).
  const cut::CutMesh& mesh() const { return *mesh_; }
  /// The cutter (options, degeneracy count).
  const cut::Cutter& cutter() const { return *cutter_; }
  /// The augmented system (m, current K, constraints).
  const linalg::AugmentedSystem& system() const { return *system_; }
  /// First of the three DOFs of node v, or −1 (fixed from the start, or never used).
  int dof(Index v) const { return node_dof_[static_cast<size_t>(v)]; }
  /// Current displacement of every node (3 × num_nodes, m): the last successful solution;
  /// zero for nodes fixed from the start.
  const Eigen::Matrix3Xd& displacement() const { return displacement_; }

 private:
  struct LastSolve {  // outcome of the last solve_into (reused when a step changes nothing)
    CutSolveStatus status = CutSolveStatus::kOk;
    std::string message;
    Index free_components = 0, inverted_elements = 0;
    bool solved = false;  // a valid solution for the current system and forces
  };
  struct Record {  // what the system holds for one element slot
    cut::Tet nodes{-1, -1, -1, -1};
    Eigen::Matrix<double, 3, 4> x;
  };
  std::vector<int> element_dofs(const cut::Tet& t) const;
  void add_record(Index slot, double scale);
  void assign_new_nodes(AugmentedCutStepReport& r);
  void constrain(Index v, Index& counter);
  void solve_into(AugmentedCutStepReport& r);

  material::Material material_;
  AugmentedCutOptions options_;
  std::unique_ptr<cut::CutMesh> mesh_;
  std::unique_ptr<cut::Cutter> cutter_;
  std::unique_ptr<linalg::AugmentedSystem> system_;
  std::vector<int> node_dof_;
  std::vector<char> initially_fixed_;
  std::vector<Vec3> node_force_;
  std::vector<Record> records_;
  Eigen::Matrix3Xd displacement_;
  Index free_components_ = 0;
  Index inverted_ = 0;
  double constraint_spring_ = 1;  // k̄ (N/m): K_dd += k̄ at each constrained DOF d (file comment)
  AugmentedCutStepReport initial_;
  LastSolve last_;
  RefactorizationPolicy policy_;
  SynchronousRefactorRule sync_rule_;
  double sync_cpu_ = 0;  // measured CPU of the last synchronous refactorization (0: none yet)
  int sync_count_ = 0;
};

}  // namespace incise::interactive
