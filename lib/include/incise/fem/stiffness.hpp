#pragma once
/// \file stiffness.hpp
/// Element stiffness blocks and the assembled stiffness matrix for callers that keep element
/// blocks themselves (interactive::AugmentedCutSession adds and subtracts them in a
/// linalg::AugmentedSystem). Both come from the element kernel TetKernel::tangent
/// (tet_kernels.hpp) that ElasticProblem evaluates four elements at a time: the assembled
/// ElasticProblem::tangent_matrix() at u equals the sum of the element_stiffness() blocks at u
/// to round-off.

#include <incise/core/types.hpp>
#include <incise/fem/tet_kernels.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/mesh_data.hpp>

#include <Eigen/SparseCore>

namespace incise::fem {

/// K_e(u) = ∂q/∂x, the 12 × 12 tangent stiffness (N/m; node-major DOF order 3a + i) of the
/// tetrahedron with reference nodes `reference` (columns, m) at nodal displacements `u` (m), for
/// `material` (thesis §3.1; (2.22) for the "linear" model, whose K_e does not depend on u):
/// the symmetric part ½(K + Kᵀ) of TetKernel::tangent's block (its node-4 blocks are symmetric
/// only to round-off). Returns false, with `k` zero, when the reference volume is not positive
/// or the element is inverted at u (log-term models).
[[nodiscard]] bool element_stiffness(const material::Material& material,
                                     const Mat34T<double>& reference, const Mat34T<double>& u,
                                     Mat12T<double>& k);

/// The stiffness matrix K = K(0) = Σ_τ K_τ(0) of `mesh` for `material` (3n × 3n, DOF
/// 3·node + i; N/m): ElasticProblem::assemble_tangent at u = 0 (FixedDofTreatment::kKeep),
/// symmetrized, so that both triangles are stored and K = Kᵀ exactly. Nodes without elements
/// keep a zero diagonal entry. Throws ParameterError as the ElasticProblem constructor does
/// (not a 3D tetrahedral mesh, missing nodes, an element with non-positive reference volume).
Eigen::SparseMatrix<double> assemble_stiffness(const mesh::MeshData& mesh,
                                               const material::Material& material);

}  // namespace incise::fem
