#pragma once
/// \file augmented_system.hpp
/// Augmented-matrix solves of a changing linear elastostatic system K a = f (Yeung, Crouch,
/// Pothen 2016, "Interactively cutting and constraining vertices in meshes using augmented
/// matrices", §3). The factor of an initial matrix K⁰ is kept; later changes of K (element
/// removals/additions, new DOFs from cuts) and Dirichlet constraints are expressed as
/// replacements of m columns (eqs. 4–6):
///
///     K^A = [ R  J ]   R = diag(K⁰, I)  (eq. 12, padded with I for new DOFs),
///           [ H  0 ]   J_{*,i} = K_{*,𝓛ᵢ} (𝓛ᵢ ∉ 𝓓) or e_{𝓛ᵢ} (𝓛ᵢ ∈ 𝓓),  H_{i,*} = e_{𝓛ᵢ}ᵀ,
///
/// and solved by the three steps of §3.2: y = R⁻¹f̂ restricted to 𝓛, GMRES on the Schur system
/// (H R⁻¹ J) a₂ = H R⁻¹ f̂ (eq. 17), a₁ = R⁻¹(f̂ − J a₂) (eq. 16). Triangular solves are
/// restricted to elimination-tree closures (§3.3). A background thread can refactor the current
/// K (§3.6). See docs/augmented.md.
///
/// DOF numbering: the caller numbers the *free* DOFs of K⁰ 0…n₀−1; DOFs held fixed for the
/// whole simulation (e.g. an anchored face) are removed from K⁰ beforehand
/// (remove_fixed_dofs()) and are passed as −1 in element DOF lists. New DOFs get n₀, n₀+1, …
/// in the order of add_dofs() calls.

#include <incise/core/name_table.hpp>
#include <incise/core/outcome.hpp>
#include <incise/linalg/capacitance_factor.hpp>
#include <incise/linalg/cholmod_factor.hpp>
#include <incise/linalg/gmres.hpp>

#include <cstdint>
#include <future>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

namespace incise::linalg {

/// Preconditioner M ≈ H S J of the Schur system (§3.5).
enum class SchurPreconditioner {
  kNone,            ///< plain GMRES
  kDiagonal,        ///< S = D⁻¹ from the LDLᵀ factor of R (permuted back)
  kTridiagonalSpai  ///< S = tridiagonal sparse approximate inverse of R (Benson &
                    ///< Frederickson 1982): min ‖R S − I‖_F column by column
};

/// Names of the Schur preconditioners (the GMRES values of the scene key
/// `schur_preconditioner`, docs/scenes.md): "hsj" is H S J with S = D⁻¹.
inline constexpr NameTable<SchurPreconditioner, 3> kSchurPreconditionerNames{{{
    {SchurPreconditioner::kDiagonal, "hsj"},
    {SchurPreconditioner::kTridiagonalSpai, "spai"},
    {SchurPreconditioner::kNone, "none"},
}}};

/// Name from kSchurPreconditionerNames.
inline const char* to_string(SchurPreconditioner p) {
  return kSchurPreconditionerNames.name(p);
}

/// How the m×m Schur system (H R⁻¹ J) a₂ = H R⁻¹ f̂ of eq. 17 is solved.
enum class SchurSolver {
  kGmres,  ///< GMRES (§3.2): one closure-restricted solve with R per iteration, every step
  /// H R⁻¹ J formed explicitly in the capacitance form Φ + G Ψ (docs/augmented.md): G, the
  /// block of R⁻¹ on 𝓛, is kept between solve() calls while the factor is the same; a DOF
  /// that joins 𝓛 costs one closure-restricted solve R⁻¹e_{𝓛ᵢ}, changed column values only
  /// the m×m product G Ψ (Ψ holds the changes E = K − R on 𝓛 and e_k for Dirichlet columns).
  /// Its dense LU is the right preconditioner of GMRES on the exact operator, which then
  /// converges in a few iterations (the capacitance form amplifies round-off by κ(R) in the
  /// directions of R's low modes, so it is not used as a direct solve). Measured counts and
  /// costs: docs/augmented.md.
  kDirectCached
};

/// Elimination order of a synchronous refactorization (AugmentedSystem::refactor_now(
/// RefactorOrdering, bool)).
enum class RefactorOrdering {
  kOptions,  ///< AugmentedOptions::cholmod's ordering (METIS in the sessions): computed afresh
  kAmd,      ///< CHOLMOD's AMD: computed afresh, cheaper than METIS, more fill
  /// No ordering computed: the factor in use's, each DOF added since placed right after the
  /// latest-eliminated of its neighbours (CholmodFactor::analyze with a given permutation)
  kExtendCurrent
};

/// Options of an AugmentedSystem.
struct AugmentedOptions {
  /// Factorization of K⁰ (and of background refactorizations). METIS nested dissection by
  /// default: shallower elimination trees, hence smaller closures (§3.3–3.4), for more fill.
  /// Simplicial LDLᵀ by default: the solves use the simplicial form anyway (the LDLᵀ copy of a
  /// supernodal factor carries its padding as explicit zeros). Measurements: docs/augmented.md.
  CholmodOptions cholmod = {CholmodKind::kSimplicialLdl, CholmodOrdering::kMetis};
  GmresOptions gmres;  ///< GMRES for eq. 17
  SchurPreconditioner preconditioner = SchurPreconditioner::kDiagonal;
  /// Solver of eq. 17 (GMRES by default, as in the paper).
  SchurSolver schur_solver = SchurSolver::kGmres;
  /// At the start of solve(), drop from 𝓛 every changed column that is again *exactly* equal
  /// to its column of R (e.g. an element removed and added back with exactly representable
  /// sums); skipped while a background refactorization snapshot is pending (§3.6 bookkeeping).
  bool prune_unchanged_columns = true;
  /// Numerical-singularity guard on the amplification A = max|K_ii|·‖a‖₂ / (‖f̂‖₂ +
  /// max|K_ii|·‖ā‖₂) (A ≤ κ(K) for a nonsingular K): a solution with A above this is reported
  /// as kSingularModifiedSystem and zeroed (GMRES can "converge" on a numerically singular
  /// eq. 17, e.g. after a cut frees a component, and return a huge, meaningless a). > 0.
  /// 1e12 = 1/(default gmres.tolerance): beyond it the error bound κ·tolerance ≥ A·tolerance
  /// exceeds 1, so not one digit of a is certified.
  double max_amplification = 1e12;
  /// Accuracy warning: A above this (the solve still ok() when A ≤ max_amplification) sets
  /// AugmentedReport::amplification_warning. > 0. 1e8: κ ≥ A, so the solution may have lost
  /// half of double precision's 16 digits (ε·A > 2e-8).
  double warn_amplification = 1e8;
  /// SchurSolver::kDirectCached: keep the dense factorization of the capacitance matrix
  /// between solves and update it for the columns that joined, left or changed
  /// (CapacitanceFactor: Sherman–Morrison–Woodbury on a fresh LU, O(m²k) per solve, fresh
  /// again when the update would cost more), instead of an O(m³) LU at every solve. The
  /// factor of R changing (refactorization) starts it afresh. Off here (the paper's per-solve
  /// LU; with the update, the yeung2016 verification's beam left GMRES at a true Schur residual
  /// of 3.8e-12 against the 1e-12 it asserts); AugmentedCutOptions turns it on.
  bool update_capacitance = false;
  /// SchurSolver::kDirectCached, §3.6: prepare the swap in the background. When a background
  /// factorization has finished, the next solve does not swap it in yet but hands it back to
  /// a background thread that computes G = H R⁻¹ Hᵀ of the new factor for the columns that
  /// will stay in 𝓛 after the swap (changed since the snapshot, and 𝓓); a later solve swaps
  /// it in with that G as its cache, so the swap's solve computes only the columns that joined
  /// since (without it: every column changed while the job ran, in the frame thread — the
  /// 150–470 ms swap frames of docs/augmented.md, "Refactorization policy"). Off here;
  /// AugmentedCutOptions turns it on. wait_for_refactorization() prepares and swaps in one call.
  bool prepare_swap = false;
  /// SchurSolver::kDirectCached: the dense work of a frame through the BLAS/LAPACK the process
  /// loads (dense_blas.hpp; OpenBLAS here): the capacitance LU and its many-right-hand-side
  /// solves (LAPACK dgetrf/dgetrs), and the new columns of G blocked per supernode (dgemm/dtrsm
  /// in ClosureLdlSolver::solve_restricted_block). False: Eigen's LU and entry-by-entry loops
  /// (compiled for baseline x86-64: SSE2), kept for the comparison of docs/augmented.md,
  /// "Frame maximum (issue 17)". The solutions agree to round-off (GMRES on the exact operator
  /// either way).
  bool blas_kernels = true;
  /// §3.6, overlapping refactorizations: while a background job is pending and at least this
  /// many columns have changed since its snapshot (the swap would leave them in 𝓛), a second
  /// job may start from the current K (start_refactorization()); whichever finishes its
  /// factorization first among the newer is used, an older one still running is abandoned
  /// (its thread finishes unobserved). 0: one job at a time. Off by default: measured on the
  /// liver path, docs/augmented.md "Stale background jobs (issue 17)".
  int overlap_stale_columns = 0;
  /// §3.6 with prepare_swap: the background job goes on from its factorization straight to G of
  /// the columns that will stay in 𝓛 as the last solve() saw them (changed since the snapshot,
  /// and 𝓓; each solve publishes them), without waiting for a solve to poll it; a later solve
  /// swaps it in and makes only the columns missing from that G. Off: the finished
  /// factorization waits for a poll, which hands it back for the preparation (two polls per
  /// swap). Off here; AugmentedCutOptions turns it on (docs/augmented.md, issue 17).
  bool prepare_in_job = false;
  /// Threads of step 3's full backward substitution (ClosureLdlSolver): 1 = serial, ≥ 1. The
  /// pass streams all of L and is memory-bound, so extra threads help as far as a core adds
  /// memory bandwidth (docs/augmented.md). The result is bit-identical for any value. Leave at
  /// 1 when the core is needed elsewhere, e.g. by a background refactorization (§3.6).
  int solve_threads = 1;
  /// §3.6 and "Fixed DOFs of K⁰": a refactorization (background job or refactor_now()) factors
  /// K with the rows and columns of the DOFs constrained at its snapshot replaced by their
  /// diagonal entry (the prescribed values go to the right-hand side, f̂_d = K_dd ā_d), so
  /// those DOFs leave 𝓛 while they stay constrained: m after a swap excludes 𝓓. A DOF of that
  /// set released later rejoins 𝓛 with the columns coupled to it (their row of K is no longer
  /// that of the factored matrix). False: the base is the unconstrained K and 𝓓 stays in 𝓛
  /// (the paper's eq. 5 second case). Off here (the paper's form); interactive_options() turns
  /// it on. Measured: docs/augmented.md, "Constrained DOFs eliminated at a refactorization
  /// (issue 17)".
  bool eliminate_constrained = false;
};

/// The options of the interactive sessions at organ scale (interactive::AugmentedCutSession,
/// the 3D needle's augmented path): a supernodal CHOLMOD factor (METIS kept), eq. 17
/// preconditioned by the explicit H R⁻¹ J in capacitance form (SchurSolver::kDirectCached), its
/// factorization updated between solves, a background factor's G prepared before its swap by
/// the job itself (prepare_in_job). Why,
/// with the measurements: docs/cutting.md, docs/augmented.md.
inline AugmentedOptions interactive_options() {
  AugmentedOptions o;
  o.cholmod.kind = CholmodKind::kSupernodal;
  o.schur_solver = SchurSolver::kDirectCached;
  o.update_capacitance = true;     // issue 17: updated, not refactored (docs/augmented.md)
  o.prepare_swap = true;           // issue 17: G of a new factor made in the background
  o.prepare_in_job = true;         // issue 17: no poll between factorization and G
  o.eliminate_constrained = true;  // issue 17: 𝓓 leaves 𝓛 at a refactorization
  return o;
}

/// Outcome of AugmentedSystem::solve().
enum class AugmentedStatus {
  kOk,
  kNoFactor,                ///< initialize() was not called or its factorization failed
  kSingularModifiedSystem,  ///< the modified K is singular: a DOF lost all stiffness (empty
                            ///< column), or GMRES broke down / stagnated on eq. 17
  kGmresNotConverged,       ///< GMRES hit its iteration cap before the tolerance
  kNonFinite                ///< NaN/Inf in the data (forces, element matrices)
};

/// Human-readable name of an AugmentedStatus.
const char* to_string(AugmentedStatus status);

/// A preconditioner LU of eq. 17 with a reciprocal condition estimate at or below this is
/// numerically singular and not used: GMRES runs unpreconditioned and the report says so
/// (AugmentedReport::preconditioner_dropped; the measured margins: docs/augmented.md).
inline constexpr double kMinPreconditionerRcond = 1e-13;

/// Report of one augmented solve (one "update step" of the paper).
/// message: what the caller can do when status != kOk.
struct [[nodiscard]] AugmentedReport
    : Outcome<AugmentedStatus, AugmentedStatus::kOk, AugmentedStatus::kNoFactor> {
  int n = 0;                     ///< current number of DOFs
  int m = 0;                     ///< replaced columns |𝓛| (changed columns + Dirichlet DOFs)
  int dirichlet = 0;             ///< |𝓓|
  int dirichlet_eliminated = 0;  ///< of 𝓓, DOFs eliminated in the factored matrix (not in 𝓛)
  GmresReport gmres;       ///< step 2 (kGmres; with kDirectCached: iterations 0, the LU residual)
  int schur_solves = 0;    ///< kDirectCached: restricted solves spent on new columns of G
  int pruned_columns = 0;  ///< columns dropped from 𝓛 because K equals R there again
  // Closure sizes (positions of L touched), §3.3 / Fig. 4 of the paper.
  int closure_f = 0;       ///< |closure_L(f̂)| (step 1 forward)
  int closure_y = 0;       ///< |closure_L(ŷ)| = |closure_L(𝓛)| (backward, steps 1–2)
  int closure_ja2 = 0;     ///< |closure_L(J a₂)| (step 2 forward, per iteration)
  int closure_step3 = 0;   ///< |closure_L(f̂ − J a₂)| (step 3 forward; backward is full)
  std::int64_t nnz_l = 0;  ///< |L| of the factor in use
  // Timings in seconds.
  double seconds_setup = 0;  ///< building J, H, f̂, closures and the preconditioner
  double seconds_step1 = 0;
  double seconds_step2 = 0;
  double seconds_step3 = 0;
  double seconds_total = 0;
  double seconds_swap = 0;  ///< §3.6: swapping a finished background factor in (incl. in total)
  /// CLOCK_THREAD_CPUTIME_ID of the calling thread over the whole solve (seconds_total's CPU)
  double cpu_seconds_total = 0;
  /// kDirectCached: thread CPU of the capacitance factorization (seconds_capacitance_factor's)
  double cpu_seconds_capacitance_factor = 0;
  /// kDirectCached: thread CPU of the new columns of G (seconds_new_columns's)
  double cpu_seconds_new_columns = 0;
  // Of seconds_step2 with kDirectCached: the restricted solves R⁻¹e for new columns of G, the
  // product Φ + GΨ, and the capacitance factorization (fresh or updated).
  double seconds_new_columns = 0;
  double seconds_capacitance_product = 0;
  double seconds_capacitance_factor = 0;
  /// kDirectCached: columns of Φ + GΨ kept from the last solve (same Ψ column and G: only the
  /// rows of labels new in 𝓛 summed); the others are made afresh
  int capacitance_columns_kept = 0;
  double amplification = 0;  ///< see AugmentedOptions::max_amplification
  /// amplification > AugmentedOptions::warn_amplification: digits may be lost, even when ok()
  bool amplification_warning = false;
  /// The preconditioner of eq. 17 (H S J, or the explicit H R⁻¹ J with kDirectCached) was
  /// built but its LU is numerically singular (rcond ≤ kMinPreconditionerRcond), so GMRES ran
  /// unpreconditioned; the message says so when the solve failed.
  bool preconditioner_dropped = false;
  /// rcond estimate of the preconditioner's LU (NaN: none built — kNone, or m = 0)
  double preconditioner_rcond = std::numeric_limits<double>::quiet_NaN();
  /// kDirectCached with update_capacitance: the capacitance factorization was made fresh in
  /// this solve (first solve, new factor of R, or the cost rule); else it was updated.
  bool capacitance_refreshed = false;
  /// kDirectCached with update_capacitance: rank of the update to the last fresh one (0: fresh)
  int capacitance_rank = 0;
  /// kDirectCached with update_capacitance: the cost rule's inputs (CapacitanceUpdate::
  /// needed_rank, update_flops, fresh_flops; 0 when the factorization was fresh without it)
  int capacitance_needed_rank = 0;
  double capacitance_update_flops = 0;
  double capacitance_fresh_flops = 0;
  bool refactorization_swapped = false;  ///< a background factor replaced the old one here
  FactorStatus refactorization_status = FactorStatus::kOk;  ///< of a finished background job
};

/// Thread CPU seconds of the steps that made a factor of R (AugmentedSystem::factorization_cpu):
/// CHOLMOD's symbolic analysis (ordering, elimination tree, pattern of L), its numeric
/// factorization, the LDLᵀ copy with the closure solver and §3.5 data, and — for a background
/// factor with prepare_swap — the preparation of G of the kept columns (0 otherwise).
struct FactorizationCpu {
  double analyze = 0;
  double factorize = 0;
  double extract = 0;
  double prepare = 0;
};

/// Result of remove_fixed_dofs().
struct ReducedMatrix {
  SparseMatrix matrix;            ///< rows/columns of the free DOFs, in increasing order
  std::vector<int> full_to_free;  ///< full index → free index, −1 for fixed DOFs
};

/// Removes the rows and columns of permanently fixed DOFs (zero displacement) from a full
/// symmetric matrix: the free-free block K_FF of §3.1 ("the reduced stiffness matrix").
ReducedMatrix remove_fixed_dofs(const SparseMatrix& k, const std::vector<bool>& fixed);

/// The augmented system of §3.1 with the solution method of §3.2–3.6. Not thread-safe: one
/// thread issues updates and solves; the optional background refactorization runs in its own
/// thread with its own CHOLMOD common and touches no member of this object.
class AugmentedSystem {
 public:
  explicit AugmentedSystem(AugmentedOptions options = {});
  ~AugmentedSystem();
  AugmentedSystem(const AugmentedSystem&) = delete;
  AugmentedSystem& operator=(const AugmentedSystem&) = delete;

  /// Factors K⁰ (symmetric, both triangles stored, positive definite on the free DOFs) and
  /// resets all changes, constraints and forces. Returns the factorization status; any status
  /// but kOk — kTinyPivot included: the solves need R⁻¹ itself — leaves no factor, and solve()
  /// reports kNoFactor with factorization_message(). Throws UsageError for a non-square or
  /// non-symmetric pattern.
  [[nodiscard]] FactorStatus initialize(const SparseMatrix& k0);
  /// CholmodFactor's message of the last initialize() (empty when it succeeded).
  const std::string& factorization_message() const;
  /// Status of the last initialize() (kNotAnalyzed before the first; kOverMemoryBudget when
  /// AugmentedOptions::cholmod.memory_budget_bytes refused the factorization).
  FactorStatus factorization_status() const;
  /// Wall seconds the factor in use took to make (CHOLMOD factorization, its LDLᵀ copy and the
  /// §3.5 preconditioner data), in initialize() or in the background job that was swapped in;
  /// 0 without a factor. The cost model of an automatic §3.6 refactorization policy.
  double factorization_seconds() const;
  /// CPU seconds (CLOCK_THREAD_CPUTIME_ID) of the thread that made the factor in use — the
  /// background job's own thread for a swapped-in one (threads CHOLMOD or BLAS start are not
  /// counted); 0 without a factor.
  double factorization_cpu_seconds() const;
  /// The split of the factor in use's CPU time (zeros without a factor); prepare is not part of
  /// factorization_cpu_seconds().
  FactorizationCpu factorization_cpu() const;

  /// Current number of DOFs n = n₀ + added DOFs.
  int num_dofs() const { return n_; }
  /// Order of the matrix whose factor is in use (n₀, or larger after a refactorization).
  int factored_dofs() const { return n_base_; }

  /// Appends `count` new DOFs (e.g. 3 for a node duplicated by a cut) with zero stiffness and
  /// zero force; returns the index of the first. They must receive stiffness (add_element)
  /// before solve(), or solve() reports kSingularModifiedSystem.
  int add_dofs(int count);

  /// K ← K + scale·Kₑ on the rows/columns `dofs` (entries −1 are fixed DOFs and skipped):
  /// adds (scale = 1) or removes (scale = −1) an element's stiffness (§3.1: "affected elements
  /// can be removed ... by subtracting their contributions"). Kₑ must be square, symmetric and
  /// sized like `dofs`. Every touched column joins 𝓛.
  void add_element(const std::vector<int>& dofs, const Eigen::MatrixXd& ke, double scale = 1.0);

  /// Prescribes displacement `value` (m) at DOF `dof` (joins 𝓓 and 𝓛; eq. 5 second case).
  /// Re-imposing updates the value.
  void impose_dirichlet(int dof, double value);
  /// Releases the constraint of `dof` (no-op when not constrained). The column leaves 𝓛 when K
  /// agrees with R there. A DOF eliminated in the factored matrix (or in a pending job's
  /// snapshot; eliminate_constrained) rejoins 𝓛 with every column coupled to it.
  void release_dirichlet(int dof);
  /// Whether `dof` is constrained.
  bool is_constrained(int dof) const { return dirichlet_.count(dof) != 0; }

  /// Sets the external force vector f (N), size num_dofs().
  void set_force(const Eigen::VectorXd& f);
  /// Current external force (size num_dofs()).
  const Eigen::VectorXd& force() const { return f_; }

  /// Solves the current system: `displacement` (size n, prescribed values at 𝓓) and `reaction`
  /// (size n, zero off 𝓓): reaction_d = (K a)_d − f_d, the force the constraint exerts, so that
  /// K a = f + reaction. Polls the background refactorization first (with prepare_in_job,
  /// after publishing the columns the pending job is to prepare G for).
  AugmentedReport solve(Eigen::VectorXd& displacement, Eigen::VectorXd& reaction);

  /// 𝓛: sorted indices of replaced columns (changed columns, new DOFs, Dirichlet DOFs), without
  /// the constrained DOFs eliminated in the factored matrix (eliminate_constrained).
  std::vector<int> replaced_columns() const;
  /// Number of replaced columns m = |𝓛|.
  int num_replaced() const;
  /// SchurSolver::kDirectCached: the columns of 𝓛 on the factored DOFs whose column of G is not
  /// cached for the factor in use, i.e. the restricted solves the next solve() would make
  /// (AugmentedReport::schur_solves) if no background factor is swapped in first.
  int columns_without_g() const;
  /// SchurSolver::kDirectCached: the capacitance matrix Φ + GΨ = H R⁻¹ J (up to round-off) of
  /// the last solve, rows and columns in the order of 𝓛 at that solve (empty before the first).
  const Eigen::MatrixXd& last_capacitance_matrix() const { return product_; }
  /// The current stiffness K (n × n, both triangles), assembled from the base and changes.
  SparseMatrix current_matrix() const;

  /// §3.6: starts factoring a snapshot of the current K in a background thread (own CHOLMOD
  /// common, own CholmodFactor). Returns false (and does nothing) unless
  /// may_start_refactorization().
  bool start_refactorization();
  /// Whether start_refactorization() would start a job: none pending, or one pending whose
  /// snapshot is stale by AugmentedOptions::overlap_stale_columns and no second one.
  bool may_start_refactorization() const;
  /// Background jobs pending (0, 1, or 2 with overlap_stale_columns).
  int refactorizations_pending() const { return (job_.valid() ? 1 : 0) + (job2_.valid() ? 1 : 0); }
  /// Background jobs abandoned so far because a newer snapshot's factorization finished first.
  int refactorizations_abandoned() const { return abandoned_count_; }
  /// Whether a background refactorization is running or finished but not yet swapped in.
  bool refactorization_pending() const { return job_.valid(); }
  /// Whether the pending job's current stage (factorization, or the preparation of G) has
  /// finished, so that the next poll_refactorization() acts on it; false without a job.
  bool refactorization_stage_finished() const;
  /// If the background job has finished, swaps its factor in (m drops to the columns changed
  /// since the job started) and returns true; a second job then becomes the pending one, and if
  /// the second finished its factorization while the first is still running, the first is
  /// abandoned and the second goes on as the first would (refactorizations_abandoned()). A
  /// failed job is dropped; its status is stored in last_refactorization_status().
  bool poll_refactorization();
  /// Blocks until the background job (if any) finishes, then swaps as poll does; with a second
  /// (overlapping) job, then also that one, so that none is pending on return.
  bool wait_for_refactorization();
  /// Factors the current K now, in the calling thread (a pending background job is waited for
  /// and swapped first), and swaps it in: m drops to |𝓓| (to 0 with eliminate_constrained). The
  /// per-frame "refactor every step" strategy of docs/augmented.md (organ scale). Returns whether a
  /// factor was swapped in (false: the factorization failed, the old factor stays;
  /// last_refactorization_status() says why).
  bool refactor_now();
  /// refactor_now() with the elimination order of `ordering` (RefactorOrdering; cheaper than a
  /// METIS analysis on the liver: docs/augmented.md, "Synchronous refactorization (issue 17)"),
  /// and with `abandon_pending` the pending background jobs
  /// dropped instead of waited for (their snapshots are older than the current K; their threads
  /// run to their end unobserved: refactorizations_abandoned() counts them).
  bool refactor_now(RefactorOrdering ordering, bool abandon_pending);
  /// RefactorOrdering::kExtendCurrent's elimination order for `k` (the current K, or any matrix
  /// of order ≥ factored_dofs() with the pattern of its new DOFs): the factor in use's
  /// permutation, each DOF ≥ factored_dofs() placed right after the latest-eliminated of its
  /// neighbours < factored_dofs() (at the end without one); perm[k] = the DOF eliminated k-th.
  std::vector<int> extended_ordering(const SparseMatrix& k) const;
  /// Status of the last finished background factorization.
  FactorStatus last_refactorization_status() const { return last_refactor_status_; }

 private:
  using Column = std::vector<std::pair<int, double>>;  // sorted by row
  // Factor, matrix and preconditioner data of R.
  struct Base;
  // 𝓛, J, H and f̂ of one solve, with their closures.
  struct Augmentation;
  // Dense LU of an m×m approximation of H R⁻¹ J (GMRES's right preconditioner).
  struct SchurLu;
  // `eliminated`: sorted DOFs whose rows and columns are replaced by their diagonal entry in
  // the factored matrix (eliminate_constrained; those with a positive diagonal).
  // `ordering`: the permutation to analyze with (CholmodFactor::analyze; empty: the options').
  static std::unique_ptr<Base> make_base(SparseMatrix matrix, std::unique_ptr<CholmodFactor> factor,
                                         const AugmentedOptions& options,
                                         const std::vector<int>& eliminated = {},
                                         const std::vector<int>& ordering = {});
  // The DOFs a refactorization of the current K eliminates (𝓓 when eliminate_constrained).
  std::vector<int> constrained_to_eliminate() const;
  // Whether DOF j is eliminated in the factored matrix and still constrained (not in 𝓛).
  bool eliminated_now(int j) const;
  Column column_of(int j) const;
  const Column* changed_column(int j) const;
  void touch_column(int j);
  bool swap_in(std::unique_ptr<Base> base, const std::set<int>& changed_since);
  // prepare_swap: G of the finished factor `base` on the columns that stay in 𝓛 after its
  // swap, in a background job; false when there is nothing to prepare (swap now).
  bool start_preparing(std::unique_ptr<Base>& base);
  int prune_unchanged_columns();
  // The steps of solve(), in order (defined in augmented_solve.cpp with their equations).
  bool augment(Augmentation& aug, AugmentedReport& report);
  void find_closures(Augmentation& aug, AugmentedReport& report);
  Eigen::MatrixXd hsj_matrix(const Augmentation& aug) const;
  Eigen::VectorXd schur_rhs(const Augmentation& aug);
  const Eigen::MatrixXd& capacitance_matrix(const Augmentation& aug, int& solves,
                                            AugmentedReport& report);
  Eigen::VectorXd solve_schur_system(Augmentation& aug, const Eigen::VectorXd& rhs,
                                     const SchurLu& hsj, AugmentedReport& report);
  void back_substitute(Augmentation& aug, const Eigen::VectorXd& a2, Eigen::VectorXd& displacement);
  void scatter_schur_solution(const Augmentation& aug, const Eigen::VectorXd& a2,
                              Eigen::VectorXd& displacement, Eigen::VectorXd& reaction) const;
  void conclude(const Augmentation& aug, Eigen::VectorXd& displacement, Eigen::VectorXd& reaction,
                AugmentedReport& report) const;

  AugmentedOptions options_;
  std::unique_ptr<Base> base_;
  int n_ = 0;
  int n_base_ = 0;
  std::unordered_map<int, Column> changed_;  // current K columns differing from R
  std::map<int, double> dirichlet_;          // 𝓓 with prescribed values
  Eigen::VectorXd f_;
  std::set<int> changed_since_snapshot_;
  // prepare_in_job: the labels the pending job prepares G for once factored (published by each
  // solve; shared with the job's thread under its mutex).
  struct KeepBoard;
  std::shared_ptr<KeepBoard> board_;
  void publish_keep();
  bool snapshot_active_ = false;
  std::future<std::unique_ptr<Base>> job_;
  bool job_preparing_ = false;  // job_ is the prepare_swap stage (G of a finished factor)
  // overlap_stale_columns: a newer job (factorization stage only) and its changed columns;
  // promoted to job_ when job_ is swapped in or abandoned.
  std::future<std::unique_ptr<Base>> job2_;
  std::set<int> changed_since_snapshot2_;
  // eliminate_constrained: the DOFs the pending jobs' snapshots eliminate (both jobs); a release
  // of one of them touches its coupled columns so that they stay in 𝓛 after the swap.
  std::vector<int> job_eliminated_, job2_eliminated_;
  // Abandoned jobs: std::async futures block on destruction, so they are kept until ready.
  std::vector<std::future<std::unique_ptr<Base>>> abandoned_;
  int abandoned_count_ = 0;
  void promote_second_job();
  void reap_abandoned(bool wait);
  FactorStatus last_refactor_status_ = FactorStatus::kOk;
  double diag_scale_ = 1;  // max |K⁰_ii|: entries below 1e-13·diag_scale_ count as zero
  // SchurSolver::kDirectCached: G = (R⁻¹) on the base DOFs of 𝓛 of the last solve, kept while
  // the base factor is the same.
  std::uint64_t base_generation_ = 0;  // bumped whenever base_ is replaced
  std::uint64_t g_generation_ = 0;     // base_generation_ g_ was computed with (0: none)
  std::vector<int> g_l_;               // its DOFs (sorted)
  Eigen::MatrixXd g_;
  // kDirectCached: the last capacitance matrix Φ + GΨ with its 𝓛, Ψ columns ((row, value) in
  // summation order) and Dirichlet flags, reused for the columns whose Ψ is the same on the same
  // G (capacitance_matrix()).
  std::uint64_t product_generation_ = 0;
  std::vector<int> product_l_;
  std::vector<std::vector<std::pair<int, double>>> product_psi_;
  std::vector<char> product_dirichlet_;
  Eigen::MatrixXd product_;
  // update_capacitance: the kept factorization of H R⁻¹ J and the base generation it is of.
  CapacitanceFactor capacitance_;
  std::uint64_t capacitance_generation_ = 0;
  // Workspace.
  std::vector<int> pos_in_l_;
};

}  // namespace incise::linalg
