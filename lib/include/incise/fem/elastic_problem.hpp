#pragma once
/// \file elastic_problem.hpp
/// The static elastic body as an incise::Problem (thesis §2.3–2.4, §3.1): potential energy
/// Π(u) (2.40), its gradient f_int(u) − f_ext, the tangent K(u) matrix-free and assembled into a
/// fixed sparse pattern, lumped mass (§2.5), fixed nodes and loads.
///
/// Unknowns: nodal displacements u (metres), node-major: DOF 3·node + component.
/// Sign convention (core/problem.hpp): gradient(u) = ∇Π = Σ_τ q_τ(u) − f_ext, where
/// q_τ = −f_el is the element's internal force (tet_kernels.hpp).
///
/// Fixed DOFs: gradient() and hessian_product() are *not* projected (reaction forces stay
/// visible); project() zeroes fixed components. The assembled tangent offers two treatments
/// (FixedDofTreatment): kKeep (the raw K), or kIdentity — rows and columns of fixed DOFs zeroed
/// and a 1 placed on their diagonal, so the matrix stays n×n with an unchanging pattern and is
/// symmetric positive definite whenever the free block is. With kIdentity, solving K x = P r for
/// a projected right-hand side gives x with zero fixed components.

#include <incise/core/parallel.hpp>
#include <incise/core/problem.hpp>
#include <incise/core/simd_scalar.hpp>
#include <incise/core/types.hpp>
#include <incise/fem/tet_kernels.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/mesh_data.hpp>

#include <Eigen/SparseCore>
#include <cstdint>
#include <functional>
#include <vector>

namespace incise::fem {

/// Counted flops per element evaluation for one material (obtained by running the kernels once
/// with incise::Counted; see element_flops()).
struct ElementFlops {
  std::uint64_t energy = 0;                    ///< v·W
  std::uint64_t force = 0;                     ///< internal forces q (Table 4.3 "Force")
  std::uint64_t force_and_energy = 0;          ///< q and v·W from one kinematics evaluation
  std::uint64_t force_energy_and_product = 0;  ///< q, v·W and K_e·d (Newton line-search point)
  std::uint64_t force_and_product = 0;  ///< q and K_e·d ((4.3)+(4.4), Table 4.3 "Derivative")
  std::uint64_t product = 0;            ///< K_e·d alone (matrix-free product)
  std::uint64_t curvature = 0;          ///< dᵀK_e d alone (the secant's slope)
  std::uint64_t force_and_tangent = 0;  ///< q and the full 12×12 K_e
  std::uint64_t tangent = 0;            ///< the 12×12 K_e alone (assembly, diagonal)
};

/// Counts the flops of every kernel for `material` at a generic, non-inverted deformation
/// (branches in the kernels depend on parameters only, e.g. γ = 0 skips the exponential).
ElementFlops element_flops(const material::Material& material);

/// How fixed DOFs appear in the assembled tangent (see file comment).
enum class FixedDofTreatment {
  kKeep,     ///< the raw tangent K(u)
  kIdentity  ///< fixed rows/columns zeroed, unit diagonal
};

/// A point force on a node (newtons).
struct PointLoad {
  Index node = 0;
  Vec3 force = Vec3::Zero();
};

/// Nodes whose coordinate `axis` (0,1,2) lies within `tolerance` of `value` (metres).
std::vector<Index> nodes_on_plane(const mesh::MeshData& mesh, int axis, double value,
                                  double tolerance = 1e-9);

/// Nodes inside the closed box [lo, hi] (metres).
std::vector<Index> nodes_in_box(const mesh::MeshData& mesh, const Vec3& lo, const Vec3& hi);

/// Boundary faces (mesh::boundary_faces of the tetrahedra `tets`, outward) whose three vertices
/// lie within `tolerance` (m) of the plane {x : x[axis] = value}. Throws UsageError when axis is
/// not 0, 1 or 2.
mesh::CellMatrix boundary_faces_on_plane(const Eigen::Matrix3Xd& points,
                                         const mesh::CellMatrix& tets, int axis, double value,
                                         double tolerance = 1e-9);

/// Consistent nodal loads of a uniform dead-load traction t (N/m², reference configuration) on
/// linear triangles: each column of `faces` (3 vertex indices into `points`, m) of area A adds
/// A·t/3 to the three DOFs 3·v + i of `f` (N) of each of its vertices v — the exact consistent
/// load of a constant traction on a linear triangle, totalling t·A. Returns Σ A (m²). Throws
/// UsageError when `faces` has not 3 rows, `f` not 3·points.cols() entries, a vertex index is
/// out of range or t is not finite.
double add_surface_traction(const Eigen::Matrix3Xd& points, const mesh::CellMatrix& faces,
                            const Vec3& traction, VecX& f);

/// Elements per chunk of the element loops (a multiple of 4; a mesh of ≤ 4,096 elements is one
/// chunk; docs/fem_performance.md "Element loops on T threads"): never depends on the threads.
inline constexpr Index kElementChunk = 256;

/// Instruction set of the element loops' four-wide (Lanes4) kernels. kAvx: the same operations
/// on 256-bit registers (no FMA), so every result is bitwise that of kBaseline (x86-64 SSE2);
/// built by GCC on x86-64 outside sanitizer builds, used when the CPU has AVX.
enum class KernelIsa { kBaseline, kAvx };
/// True when this build has the kernels of `isa` and the CPU runs them.
bool kernel_isa_available(KernelIsa isa);
/// kAvx when available, else kBaseline: the default of every ElasticProblem.
KernelIsa best_kernel_isa();
/// "baseline" or "avx".
const char* to_string(KernelIsa isa);

/// Elastic body made of linear tetrahedra of one material. See file comment for conventions.
/// Element loops visit the elements in an internal order (sorted by smallest node index, for
/// memory locality) four at a time; element and node numbering seen by callers are the mesh's.
///
/// Threads: every element loop (energy, gradient, fused gradient+energy, K·d, the curvature
/// dᵀKd, the fused gradient+energy+product, the diagonal, tangent assembly) runs on threads()
/// threads
/// (core/parallel.hpp). The sweep order is cut into fixed chunks of kElementChunk elements;
/// chunks sharing a node are coloured apart and run in colour order, so every nodal value and
/// matrix entry is summed in one fixed order (colour, then sweep order inside the chunk), and the
/// energy is the sum of per-chunk partial sums in chunk order. Every result is therefore bitwise
/// the same for every thread count (test fem_threads_test).
class ElasticProblem : public Problem {
 public:
  /// Takes a 3D tetrahedral mesh (reference configuration). Throws ParameterError when the
  /// mesh is not 3D tetrahedral, references missing nodes, or has an element with
  /// non-positive reference volume (naming the element).
  ElasticProblem(const mesh::MeshData& mesh, const material::Material& material);

  // --- constraints and loads -------------------------------------------------------------
  /// Fix all three components of the given nodes (u = 0 there). Throws UsageError for a bad
  /// node index.
  void fix_nodes(const std::vector<Index>& nodes);
  /// Fix one DOF (3·node + component).
  void fix_dof(Eigen::Index dof);
  /// Remove all constraints.
  void clear_constraints();
  /// Add a point load (N).
  void add_point_load(const PointLoad& load);
  /// Add the body force ρ·g (g in m/s², e.g. (0,0,−9.81)), lumped: each node receives a
  /// quarter of ρ·g·v(τ) from every incident tetrahedron (§2.5).
  void add_gravity(const Vec3& g);
  /// Add a uniform dead-load traction t (N/m², reference configuration) on the boundary faces
  /// (mesh::boundary_faces) lying in the plane {x : x[axis] = value} (within `tolerance` m),
  /// by add_surface_traction: A·t/3 per vertex of each triangle of area A.
  /// Returns the total area loaded (m²); 0 when no boundary face lies in the plane.
  double add_traction_on_plane(int axis, double value, const Vec3& traction,
                               double tolerance = 1e-9);
  /// Remove all loads.
  void clear_loads();
  /// f_ext (N), length size().
  const VecX& external_force() const { return f_ext_; }

  // --- incise::Problem --------------------------------------------------------------------
  Eigen::Index size() const override { return 3 * static_cast<Eigen::Index>(num_nodes()); }
  /// Π(u) = Σ v(τ) W(C_τ) − f_extᵀ u (J). +∞ and kInverted when an element with a log-term
  /// material has det F ≤ 0; kNonFinite when the sum is not finite otherwise.
  [[nodiscard]] EvalStatus energy(const VecX& u, double& energy) override;
  /// g = Σ q_τ(u) − f_ext (N), not projected. On kInverted g is zero and *energy = +∞.
  [[nodiscard]] EvalStatus gradient(const VecX& u, VecX& g, double* energy = nullptr) override;
  /// out = K(u)·d matrix-free (element products (4.4), §3.1), not projected. On kInverted out
  /// is zero.
  [[nodiscard]] EvalStatus hessian_product(const VecX& u, const VecX& d, VecX& out) override;
  /// c = dᵀK(u)d as Σ_τ d_τᵀ(K_τ d_τ) over the elements, each share v(τ)(S : dGᵀdG + ½ dS : dC)
  /// from (4.4) without forming K_τ d_τ (TetKernel::curvature), summed like the energy
  /// (per-chunk partial sums in chunk order: the same value for every thread count and
  /// instruction set) — one sweep without the scatter of K·d and without a global vector; the
  /// value of d·hessian_product(u, d) up to rounding. With set_assembled_product: that product
  /// and the dot. kInverted when an element is inverted at u.
  [[nodiscard]] EvalStatus hessian_curvature(const VecX& u, const VecX& d,
                                             double& curvature) override;
  /// K(u) assembled once (assemble_tangent, kKeep, then copied into 3×3 node blocks) and the
  /// function d ↦ K(u)·d by the node-block gather of the assembled product (AVX or scalar by
  /// kernel_isa(), on threads() threads; results independent of the thread count): the same
  /// operator as hessian_product(u, ·) up to rounding (other summation order), 2 flops per
  /// stored entry instead of an element sweep each. With set_assembled_product on, the product
  /// of that K. Empty when an element is inverted at u. Overwrites tangent_matrix(); the
  /// function holds its own copy of K (≈ 100 bytes per coupled node pair) and stays valid while
  /// this problem lives.
  std::function<EvalStatus(const VecX&, VecX&)> assembled_hessian(const VecX& u) override;
  /// One element sweep (TetKernel::forces_energy_and_product); results equal gradient() and
  /// hessian_product() evaluated separately.
  [[nodiscard]] EvalStatus gradient_energy_product(const VecX& u, const VecX& d, VecX& g,
                                                   double& energy, VecX& out) override;
  /// Diagonal of K(u) (from element tangents; with set_assembled_product, from the assembled
  /// K). Fixed DOFs get 1. Returns false if inverted.
  bool hessian_diagonal(const VecX& u, VecX& diag) override;
  /// True for a material with linear geometry (Material::linear_geometry(), the linear model):
  /// Π = ½uᵀKu − f_extᵀu with constant K (the loads are dead loads).
  bool energy_is_quadratic() const override { return material_.linear_geometry(); }
  void project(VecX& v) const override;
  bool is_fixed(Eigen::Index i) const override { return fixed_[static_cast<std::size_t>(i)] != 0; }
  /// ‖f_ext‖₂ over free DOFs.
  double external_force_norm() const override;
  /// ρ·v(τ)/4 per incident tetrahedron, per DOF (kg).
  const VecX& lumped_mass() const override { return mass_; }
  /// Flops counted in all evaluations so far (element counts × evaluations + assembly adds).
  std::uint64_t flops() const override { return flops_; }

  // --- assembled tangent --------------------------------------------------------------------
  /// Assembles K(u) into the fixed pattern (built once, on first use, with an element-to-entry
  /// scatter map; later calls only overwrite values). Returns kInverted (matrix values then
  /// unspecified) when an element is inverted.
  [[nodiscard]] EvalStatus assemble_tangent(
      const VecX& u, FixedDofTreatment treatment = FixedDofTreatment::kIdentity);
  /// The matrix of the last assemble_tangent() (column-major, both triangles stored, n×n).
  const Eigen::SparseMatrix<double>& tangent_matrix() const { return k_; }
  /// Convenience: assemble and copy into `k`.
  [[nodiscard]] EvalStatus tangent(const VecX& u, Eigen::SparseMatrix<double>& k,
                                   FixedDofTreatment treatment = FixedDofTreatment::kIdentity);
  /// For a material with linear geometry (Material::linear_geometry(): K does not depend on u),
  /// `on` makes hessian_product() multiply by the raw tangent (kKeep) assembled once, at the
  /// first product after the call (a problem's mesh and material never change), instead of the
  /// matrix-free element products: the same K·d up to rounding, fewer flops (2 per stored entry)
  /// — worth it when many products follow (docs/needle.md "Fig. 6.14 and speed"). On one thread
  /// K is read half-stored (diagonal blocks and the blocks above), with a result bitwise equal
  /// to the full product of several threads; with kernel_isa() kAvx the full product runs three
  /// rows at once in 256-bit registers, bitwise the same again (docs/needle.md). Throws
  /// UsageError for any other material. Default off (matrix-free, §3.1).
  void set_assembled_product(bool on);
  bool assembled_product() const { return assembled_product_; }
  /// Baseline kernels on one thread: whether the assembled product reads K half-stored (default
  /// true) or full as on several threads (the same result bitwise; for benchmarks of the two).
  void set_half_stored_product(bool on) { half_stored_ = on; }
  /// Elastic forces only: f_int = Σ q_τ(u) (N).
  [[nodiscard]] EvalStatus internal_forces(const VecX& u, VecX& f_int);

  // --- threads --------------------------------------------------------------------------
  /// Threads of the element loops, 1 to kMaxThreads (ParameterError otherwise). Default:
  /// default_thread_count() (INCISE_THREADS, else all cores). Results do not depend on it.
  void set_threads(int threads);
  int threads() const { return threads_; }
  /// Instruction set of the element loops (default best_kernel_isa()); results do not depend on
  /// it (test ElasticProblemIsa.AvxEqualsBaselineBitwise). ParameterError when not available.
  void set_kernel_isa(KernelIsa isa);
  KernelIsa kernel_isa() const { return isa_; }
  /// The fixed chunk schedule of the element loops (for tests and reports).
  const ChunkSchedule& chunk_schedule() const { return schedule_; }

  // --- access ---------------------------------------------------------------------------
  Index num_nodes() const { return static_cast<Index>(points_.cols()); }
  Index num_elements() const { return static_cast<Index>(cells_.cols()); }
  const Eigen::Matrix3Xd& points() const { return points_; }
  const mesh::CellMatrix& cells() const { return cells_; }
  const material::Material& material() const { return material_; }
  const TetReference& reference(Index e) const { return refs_[static_cast<std::size_t>(e)]; }
  /// Counted flops per element kernel for this problem's material.
  const ElementFlops& element_flop_counts() const { return element_flops_; }
  /// Indices of free DOFs in increasing order (a free-DOF map for reduced systems).
  std::vector<Eigen::Index> free_dofs() const;
  /// Total reference volume (m³).
  double volume() const;

 private:
  /// Reference data of the elements at sweep positions 4k..4k+3 in SIMD lanes (Lanes4): the kernels
  /// evaluate whole blocks at once; the (num_elements mod 4) tail uses the double kernels.
  struct RefBlock {
    Mat3T<Lanes4> z_inv;
    Mat3T<Lanes4> b;
    Lanes4 volume;
  };
  /// The one element loop behind every evaluation: calls `visit(el, w, sum)` for each block of
  /// four elements (el: a Lanes4 view, fem/element_sweep.hpp `detail::Elements`; w: work arrays;
  /// sum: the chunk's partial energy), and for the elements of a block whose visit returned false
  /// (some lane inverted; the visit must not have had side effects) and for the tail, with a double
  /// view. Chunks run on threads_ threads by schedule_ when `scatters` (the visit adds into
  /// shared arrays), else in any order. `total` receives the chunks' partial sums added in chunk
  /// order. Returns false when a double visit fails.
  template <class Visit>
  bool sweep(bool scatters, double& total, Visit&& visit) const;
  /// f_int = Σ q_τ(u), the force sweep of internal_forces() and of gradient() without Π (on
  /// inversion f_int is zeroed and the result is false; finiteness is the caller's test).
  bool force_sweep(const VecX& u, VecX& f_int);
  void build_schedule();
  /// The element tangents at u (TetKernel::tangent), each handed to `sink(el, k)` (el: the
  /// element view, k: its 12×12 tangent) — the sweep of assemble_tangent() and
  /// hessian_diagonal(), which differ only in what they keep of each tangent.
  template <class Sink>
  bool tangent_sweep(const VecX& u, Sink&& sink) const;
  Index num_full_blocks() const { return num_elements() / 4; }
  void build_pattern();
  /// Assembles K (kKeep) into the node blocks of the assembled product unless they exist.
  EvalStatus assemble_product_matrix(const VecX& u);
  void rebuild_mass();

  Eigen::Matrix3Xd points_;
  mesh::CellMatrix cells_;
  material::Material material_;
  std::vector<TetReference> refs_;  ///< per element, mesh order
  std::vector<Index> order_;        ///< sweep order: position → element (sorted by min node)
  std::vector<Index> sweep_cells_;  ///< node indices in sweep order, 4 per position
  std::vector<RefBlock> blocks_;    ///< sweep positions 4k..4k+3 in lanes
  std::vector<char> fixed_;
  std::vector<PointLoad> point_loads_;
  Vec3 gravity_ = Vec3::Zero();
  VecX f_ext_;
  VecX mass_;
  ElementFlops element_flops_;
  std::uint64_t flops_ = 0;
  Eigen::SparseMatrix<double> k_;
  bool assembled_product_ = false;
  bool half_stored_ = true;
  // K for the assembled product in 3×3 node blocks (empty until used): node b's blocks are
  // block_start_[b] .. block_start_[b + 1] − 1, block t couples node block_node_[t], its values
  // block_value_[9t + 3j + i] = K(3·block_node_[t] + i, 3b + j). Full storage (every
  // neighbour), built for the scalar kernel on several threads only.
  std::vector<int> block_start_, block_node_;
  std::vector<double> block_value_;
  // block_value4_: the same blocks as padded columns for the AVX gather, 12 per block:
  // [12t + 4i + j] = K(3·block_node_[t] + i, 3b + j), [12t + 4i + 3] = 0.
  std::vector<double> block_value4_;
  // The same blocks half-stored: node b's diagonal block at half_start_[b], then its blocks
  // with neighbours a > b in increasing a.
  std::vector<int> half_start_, half_node_;
  std::vector<double> half_value_;
  VecX assembled_diag_;  ///< K's diagonal (the assembled product's)
  /// Which layout the assembled product reads (each built on first use, all bitwise the same
  /// product): the AVX gather when isa_ is kAvx, else half-stored on one thread, else full.
  enum class ProductKernel { kHalf, kFull, kFullAvx };
  ProductKernel product_kernel() const;
  std::vector<int> scatter_;  ///< per element: 16 block value indices, 4 column lengths
  std::vector<int> diag_;     ///< value index of each diagonal entry
  int threads_ = 1;
  KernelIsa isa_ = best_kernel_isa();
  ChunkSchedule schedule_;       ///< chunks coloured by shared nodes (scattering loops)
  ChunkSchedule free_schedule_;  ///< the same chunks without conflicts (energy)
};

}  // namespace incise::fem
