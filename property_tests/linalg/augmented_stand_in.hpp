#pragma once
/// \file augmented_stand_in.hpp
/// Test scaffolding for the augmented-system tests (lives in the test folder, never in lib/).
///
/// STAND-IN MATRIX FAMILY: until the fem module's assembled elastic tangent is available to
/// the solver tests, element matrices come from the 3-DOF-per-node *vector Laplacian* of a
/// linear tetrahedron, Kₑ = v (G Gᵀ) ⊗ I₃ with G the 4×3 matrix of barycentric gradients. It
/// has the sparsity pattern of the elastic stiffness on the same mesh (3×3 node blocks), is
/// symmetric positive semidefinite per element and positive definite once a face is fixed,
/// which is all the augmented-system algebra (Yeung et al. 2016 §3) relies on. It is not an
/// elasticity model.
///
/// REAL FAMILY: with `CutModel::elastic` set, element matrices are the fem module's linear
/// elastic tetrahedron tangent (fem::TetKernel<material::LinearElastic>, thesis (2.22), §3.1).
///
/// `CutModel` is a tiny mesh state for randomized sequences: active/removed tetrahedra, node
/// duplication by a plane as in Yeung et al. 2016 §4.3.2, and a DOF numbering in which fixed
/// nodes (z = 0 face) are removed and duplicated nodes get new DOFs at the end.

#include <incise/fem/tet_kernels.hpp>
#include <incise/linalg/augmented_system.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/mesh_data.hpp>

#include <Eigen/Dense>

#include <array>
#include <vector>

namespace incise::test {

/// Stand-in element matrix (see file comment): 12×12, DOF order 3a + i.
inline Eigen::MatrixXd vector_laplacian_tet(const Eigen::Matrix<double, 3, 4>& x) {
  Eigen::Matrix3d z;
  for (int a = 0; a < 3; ++a) z.col(a) = x.col(a + 1) - x.col(0);
  const double vol = std::abs(z.determinant()) / 6.0;
  const Eigen::Matrix3d zi = z.inverse();  // rows: gradients of λ1..λ3
  Eigen::Matrix<double, 4, 3> g;
  g.row(1) = zi.row(0);
  g.row(2) = zi.row(1);
  g.row(3) = zi.row(2);
  g.row(0) = -(g.row(1) + g.row(2) + g.row(3));
  const Eigen::Matrix4d s = vol * g * g.transpose();
  Eigen::MatrixXd k = Eigen::MatrixXd::Zero(12, 12);
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b)
      for (int i = 0; i < 3; ++i) k(3 * a + i, 3 * b + i) = s(a, b);
  return k;
}

/// Mesh state for randomized augmented-system sequences.
struct CutModel {
  Eigen::Matrix3Xd points;
  std::vector<std::array<int, 4>> tets;
  std::vector<char> active;
  std::vector<int> node_dof;  ///< first of 3 DOFs, −1 for fixed nodes
  int num_dofs = 0;
  bool elastic = false;  ///< fem linear-elastic tangent instead of the stand-in
  material::Lame lame;   ///< used when elastic

  /// Switches to the linear-elastic family with E (Pa) and ν.
  void use_linear_elastic(double youngs, double poisson) {
    material::Parameters p;
    p.youngs_modulus = youngs;
    p.poisson_ratio = poisson;
    lame = material::Material("linear", p).lame();
    elastic = true;
  }

  /// From a tetrahedral mesh; nodes with z ≤ fixed_z are fixed (removed from K⁰).
  static CutModel from_mesh(const mesh::MeshData& m, double fixed_z = 1e-12) {
    CutModel c;
    c.points = m.points;
    for (Index e = 0; e < m.num_cells(); ++e)
      c.tets.push_back({m.cells(0, e), m.cells(1, e), m.cells(2, e), m.cells(3, e)});
    c.active.assign(c.tets.size(), 1);
    c.node_dof.assign(static_cast<size_t>(m.num_points()), -1);
    for (Index v = 0; v < m.num_points(); ++v) {
      if (m.points(2, v) > fixed_z) {
        c.node_dof[v] = c.num_dofs;
        c.num_dofs += 3;
      }
    }
    return c;
  }

  std::vector<int> dofs(int e) const {
    std::vector<int> d(12);
    for (int a = 0; a < 4; ++a)
      for (int i = 0; i < 3; ++i) {
        const int base = node_dof[tets[e][a]];
        d[3 * a + i] = base < 0 ? -1 : base + i;
      }
    return d;
  }

  Eigen::MatrixXd element_matrix(int e) const {
    Eigen::Matrix<double, 3, 4> x;
    for (int a = 0; a < 4; ++a) x.col(a) = points.col(tets[e][a]);
    if (!elastic) return vector_laplacian_tet(x);
    const fem::TetReference ref = fem::make_tet_reference(x);
    const Eigen::Matrix<double, 3, 4> u = Eigen::Matrix<double, 3, 4>::Zero();
    Eigen::Matrix<double, 3, 4> q;
    Eigen::Matrix<double, 12, 12> k;
    (void)fem::TetKernel<material::LinearElastic, double>::forces_and_tangent(
        lame, ref.z_inv, ref.b, ref.volume, u, q, k);
    return 0.5 * (k + k.transpose());  // symmetric to round-off; remove the round-off part
  }

  /// Assembles K over active elements (num_dofs × num_dofs, both triangles).
  linalg::SparseMatrix assemble() const {
    std::vector<Eigen::Triplet<double>> t;
    for (size_t e = 0; e < tets.size(); ++e) {
      if (!active[e]) continue;
      const auto d = dofs(static_cast<int>(e));
      const Eigen::MatrixXd k = element_matrix(static_cast<int>(e));
      for (int a = 0; a < 12; ++a)
        for (int b = 0; b < 12; ++b)
          if (d[a] >= 0 && d[b] >= 0) t.emplace_back(d[a], d[b], k(a, b));
    }
    linalg::SparseMatrix k(num_dofs, num_dofs);
    k.setFromTriplets(t.begin(), t.end());
    k.makeCompressed();
    return k;
  }
};

}  // namespace incise::test
