#pragma once
/// \file plane_stress_problem.hpp
/// A plane-stress slab of linear triangles as an incise::Problem (thesis §6.3): the 2D
/// analogue of ElasticProblem, with thickness d. Π(u) = Σ A d W₂ − f_extᵀu, gradient
/// Σ q_τ − f_ext (tri_kernels.hpp), the tangent matrix-free and assembled.
///
/// Unknowns: in-plane nodal displacements u (m), node-major: DOF 2·node + component (x, y).
/// hessian_product() is matrix-free (one element sweep, kinematics at u) for the nonlinear
/// models. For the linear model (models.hpp kLinearGeometry: linear strain and stress) K does
/// not depend on u: it is assembled once, on the first product, from the element tangents into
/// 2×2 node blocks, and each product is one block-sparse multiply (8 flops per block, counted);
/// test PlaneStressProblemProperty.EnergyGradientHessianChain checks it against the gradient
/// (Taylor order) and the assembled tangent for every material.
///
/// gradient() keeps its last result. Asked again at a bitwise-equal u it returns it; for the
/// linear model, asked at a u that differs from a swept evaluation's at no more than half the
/// nodes (a needle moved its nodes, §6.7), it returns g + K·Δu and Π + Δuᵀ(g + ½K·Δu) from
/// the changed nodes' blocks — exact for a quadratic Π up to rounding of order ε‖K‖‖Δu‖ — and
/// marks the result as not swept, so updates never chain. Loads added later clear it.
/// Tests: PlaneStressProblem.GradientReuseMatchesASweep.
///
/// Fixed DOFs are handled as in ElasticProblem: gradient() and hessian_product() are not
/// projected, project() zeroes fixed components, the assembled tangent gets unit diagonals at
/// fixed DOFs.
///
/// Failures: an element with det F₂ ≤ 0 under a log model gives EvalStatus::kInverted; an
/// element whose out-of-plane Newton solve (plane_stress.hpp) fails gives
/// EvalStatus::kNonFinite (Π cannot be evaluated). Either way last_outcome() names the first
/// failing element and the plane-stress status.

#include <incise/core/outcome.hpp>
#include <incise/core/problem.hpp>
#include <incise/core/types.hpp>
#include <incise/fem/tri_kernels.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/mesh_data.hpp>

#include <Eigen/SparseCore>
#include <cstdint>
#include <vector>

namespace incise::fem {

/// Counted flops per plane-stress element evaluation (TriKernel run once with incise::Counted
/// at a generic deformation; Newton iterations included as executed there).
struct TriElementFlops {
  std::uint64_t energy = 0;             ///< A·d·W₂
  std::uint64_t force = 0;              ///< internal forces q
  std::uint64_t force_and_energy = 0;   ///< q and A·d·W₂ from one kinematics evaluation
  std::uint64_t product = 0;            ///< K_e·d (matrix-free; nonlinear models)
  std::uint64_t force_and_tangent = 0;  ///< q and the 6×6 K_e
};

/// Counts the flops of the plane-stress kernels for `material` at the deformation
/// `gradient` (G₂, default a generic small-strain one). Throws UsageError when the kernels
/// fail there.
TriElementFlops tri_element_flops(
    const material::Material& material,
    const Mat2& gradient = (Mat2() << 0.011, -0.004, 0.006, -0.008).finished());

/// Report of the last evaluation of a PlaneStressProblem.
struct PlaneStressOutcome : Outcome<material::PlaneStressStatus, material::PlaneStressStatus::kOk,
                                    material::PlaneStressStatus::kOk> {
  Index element = -1;  ///< first failing element (−1 when ok)
};

/// Plane-stress slab of one material and thickness. See file comment for conventions.
class PlaneStressProblem : public Problem {
 public:
  /// Takes a 2D triangle mesh (dimension 2, points in the z = 0 plane, reference
  /// configuration) and thickness d (m). Throws ParameterError when the mesh is not 2D,
  /// references missing nodes, has an element of non-positive area (naming it) or d is not
  /// finite and > 0.
  PlaneStressProblem(const mesh::MeshData& mesh, const material::Material& material,
                     double thickness);

  // --- constraints and loads -------------------------------------------------------------
  /// Fix both components of the given nodes. Throws UsageError for a bad node index.
  void fix_nodes(const std::vector<Index>& nodes);
  /// Fix one DOF (2·node + component). Throws UsageError when out of range.
  void fix_dof(Eigen::Index dof);
  /// Add a point force (N) on `node`.
  void add_point_load(Index node, const Vec2& force);
  /// Add a uniform dead-load traction t (N/m², reference configuration) on the boundary edges
  /// whose two vertices lie within `tolerance` (m) of the line {x : x[axis] = value}: the 2D
  /// traction is t̃ = t·d (N/m) and each edge of length L adds L·t̃/2 to both its vertices
  /// (consistent for linear elements). Returns the loaded length Σ L (m). Throws UsageError
  /// when axis is not 0 or 1 or t is not finite.
  double add_traction_on_line(int axis, double value, const Vec2& traction,
                              double tolerance = 1e-9);
  /// f_ext (N), length size().
  const VecX& external_force() const { return f_ext_; }

  // --- incise::Problem --------------------------------------------------------------------
  Eigen::Index size() const override { return 2 * static_cast<Eigen::Index>(num_nodes()); }
  [[nodiscard]] EvalStatus energy(const VecX& u, double& energy) override;
  [[nodiscard]] EvalStatus gradient(const VecX& u, VecX& g, double* energy = nullptr) override;
  [[nodiscard]] EvalStatus hessian_product(const VecX& u, const VecX& d, VecX& out) override;
  /// Diagonal of K(u) from the element tangents; fixed DOFs get 1. False on failure.
  bool hessian_diagonal(const VecX& u, VecX& diag) override;
  void project(VecX& v) const override;
  bool is_fixed(Eigen::Index i) const override { return fixed_[static_cast<std::size_t>(i)] != 0; }
  /// ‖f_ext‖₂ over free DOFs.
  double external_force_norm() const override;
  /// Flops counted in all evaluations so far (element counts × evaluations).
  std::uint64_t flops() const override { return flops_; }

  /// The assembled tangent K(u) (n×n, both triangles), fixed rows and columns replaced by the
  /// identity. kInverted / kNonFinite as for gradient() (k then unspecified).
  [[nodiscard]] EvalStatus tangent(const VecX& u, Eigen::SparseMatrix<double>& k);

  /// What the last evaluation found (status ok, or the first failing element).
  const PlaneStressOutcome& last_outcome() const { return outcome_; }

  // --- access ---------------------------------------------------------------------------
  Index num_nodes() const { return static_cast<Index>(points_.cols()); }
  Index num_elements() const { return static_cast<Index>(cells_.cols()); }
  double thickness() const { return thickness_; }
  const material::Material& material() const { return material_; }
  const Eigen::Matrix2Xd& points() const { return points_; }
  const mesh::CellMatrix& cells() const { return cells_; }
  const TriReference& reference(Index e) const { return refs_[static_cast<std::size_t>(e)]; }
  const TriElementFlops& element_flop_counts() const { return element_flops_; }
  /// True when K does not depend on u (the linear model): hessian_product() then multiplies
  /// the assembled K and ignores its u argument (but for its size).
  bool has_constant_tangent() const { return constant_tangent_; }

 private:
  /// Calls visit(kernel-tag, element, x (2×3 displacements)) for every element; stops at the
  /// first non-ok status, records it in outcome_ and maps it to an EvalStatus.
  template <class Visit>
  EvalStatus sweep(const VecX& u, Visit&& visit);
  /// Assembles k_blocks_ (the constant tangent of a linear-geometry model).
  void assemble_constant_tangent();

  /// Block-sparse rows of the constant tangent: node i's blocks are the columns col[r] with
  /// values[4r .. 4r+3] (column-major 2×2) for r in [row[i], row[i+1]).
  struct NodeBlocks {
    std::vector<Index> row;
    std::vector<Index> col;
    std::vector<double> values;
  };

  Eigen::Matrix2Xd points_;
  mesh::CellMatrix cells_;
  material::Material material_;
  double thickness_ = 0.0;
  std::vector<TriReference> refs_;
  std::vector<char> fixed_;
  VecX f_ext_;
  TriElementFlops element_flops_;
  std::uint64_t flops_ = 0;
  PlaneStressOutcome outcome_;
  bool constant_tangent_ = false;  ///< the model's K is independent of u (kLinearGeometry)
  NodeBlocks k_blocks_;            ///< empty until the first product of a constant-tangent model

  /// The last successful gradient evaluation (see gradient()): `swept` when it came from an
  /// element sweep rather than from an update of an earlier one.
  struct GradientMemo {
    bool valid = false, swept = false, has_energy = false;
    VecX u, g;
    double energy = 0.0;
  };
  /// Answers gradient() from memo_ (see the class comment); false when it cannot.
  bool reuse_gradient(const VecX& u, VecX& g, double* energy);
  GradientMemo memo_;
  std::vector<Index> changed_;  ///< scratch of reuse_gradient()
};

}  // namespace incise::fem
