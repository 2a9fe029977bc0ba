#pragma once
// The independent reference of the interactive augmented tests (one definition, used by
// property_tests/interactive/augmented_cut_test.cpp and soak_test.cpp): a fresh factorization of
// the cut mesh's linear-elastic system, assembled by fem::ElasticProblem from
// CutMesh::to_mesh_data and solved by Eigen's SimplicialLDLT, and the comparison with the
// session's augmented solution.
#include <incise/fem/elastic_problem.hpp>
#include <incise/interactive/augmented_cut_session.hpp>

#include <gtest/gtest.h>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <iostream>
#include <limits>
#include <vector>

namespace incise::test {

/// Result of the independent reference solve.
struct Reference {
  bool ok = false;
  Eigen::Matrix3Xd u;  ///< displacement per session node (unused nodes: zero)
  double rcond = 1;    ///< min/max pivot of the LDLᵀ of the free block (≈ 1/κ lower bound)
};

/// Fresh factorization of the cut mesh's system: K from fem::ElasticProblem on the compacted
/// mesh, prescribed DOFs (nodes fixed from the start: 0; DOFs the session constrained: the
/// session's prescribed values, which the augmented solution carries exactly), free block
/// solved by SimplicialLDLT.
inline Reference reference_solution(const interactive::AugmentedCutSession& s,
                                    const material::Material& material,
                                    const std::vector<Vec3>& forces) {
  std::vector<Index> map;
  const mesh::MeshData md = s.mesh().to_mesh_data(false, true, &map);
  fem::ElasticProblem prob(md, material);
  Eigen::SparseMatrix<double> k;
  const VecX u0 = VecX::Zero(prob.size());
  EXPECT_EQ(prob.tangent(u0, k, fem::FixedDofTreatment::kKeep), EvalStatus::kOk);
  const Eigen::Index n = prob.size();
  std::vector<char> prescribed(static_cast<size_t>(n), 0);
  VecX abar = VecX::Zero(n), f = VecX::Zero(n);
  for (Index v = 0; v < static_cast<Index>(map.size()); ++v) {
    const Index c = map[static_cast<size_t>(v)];
    if (c < 0) continue;
    const int d = s.dof(v);
    for (int i = 0; i < 3; ++i) {
      const Eigen::Index g = 3 * c + i;
      if (v < static_cast<Index>(forces.size())) f(g) = forces[static_cast<size_t>(v)](i);
      if (d < 0) {
        prescribed[static_cast<size_t>(g)] = 1;
      } else if (s.system().is_constrained(d + i)) {
        prescribed[static_cast<size_t>(g)] = 1;
        abar(g) = s.displacement()(i, v);
      }
    }
  }
  std::vector<Eigen::Index> free_index(static_cast<size_t>(n), -1);
  Eigen::Index nf = 0;
  for (Eigen::Index g = 0; g < n; ++g)
    if (!prescribed[static_cast<size_t>(g)]) free_index[static_cast<size_t>(g)] = nf++;
  const VecX rhs_full = f - k * abar;
  VecX rhs(nf);
  std::vector<Eigen::Triplet<double>> t;
  for (int col = 0; col < k.outerSize(); ++col) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(k, col); it; ++it) {
      const Eigen::Index i = free_index[static_cast<size_t>(it.row())];
      const Eigen::Index j = free_index[static_cast<size_t>(col)];
      if (i >= 0 && j >= 0) t.emplace_back(i, j, it.value());
    }
  }
  for (Eigen::Index g = 0; g < n; ++g)
    if (free_index[static_cast<size_t>(g)] >= 0)
      rhs(free_index[static_cast<size_t>(g)]) = rhs_full(g);
  Eigen::SparseMatrix<double> kff(nf, nf);
  kff.setFromTriplets(t.begin(), t.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(kff);
  Reference out;
  if (ldlt.info() != Eigen::Success) return out;
  const VecX d = ldlt.vectorD();
  if (d.minCoeff() <= 0) {
    std::cout << "reference: min pivot " << d.minCoeff() << " max " << d.maxCoeff() << "\n";
    return out;
  }
  out.rcond = d.minCoeff() / d.maxCoeff();
  const VecX x = ldlt.solve(rhs);
  out.u = Eigen::Matrix3Xd::Zero(3, static_cast<Index>(map.size()));
  for (Index v = 0; v < static_cast<Index>(map.size()); ++v) {
    const Index c = map[static_cast<size_t>(v)];
    if (c < 0) continue;
    for (int i = 0; i < 3; ++i) {
      const Eigen::Index g = 3 * c + i;
      const Eigen::Index fi = free_index[static_cast<size_t>(g)];
      out.u(i, v) = fi >= 0 ? x(fi) : abar(g);
    }
  }
  out.ok = true;
  return out;
}

/// max over used nodes |u_session − u_ref| / max |u_ref|.
inline double relative_difference(const interactive::AugmentedCutSession& s, const Reference& ref) {
  double diff = 0, scale = 0;
  for (Index v = 0; v < s.mesh().num_nodes(); ++v) {
    if (s.mesh().unused(v)) continue;
    diff = std::max(diff, (s.displacement().col(v) - ref.u.col(v)).cwiseAbs().maxCoeff());
    scale = std::max(scale, ref.u.col(v).cwiseAbs().maxCoeff());
  }
  return scale > 0 ? diff / scale : diff;
}

/// Tolerance of the comparison: GMRES stops at relative residual 1e-14 on eq. 17, and the
/// reference itself is backward stable; both errors are amplified by at most κ(K_FF) ≤
/// 1/rcond (pivot ratio, a lower estimate of κ, hence the factor 100), floored at 1e-9.
inline double tolerance(const Reference& ref) {
  return std::max(1e-9, 100 * std::numeric_limits<double>::epsilon() / ref.rcond);
}

/// Whether the outcome of a step is admissible. Policy kFixOnFace (default) leaves no free
/// component; refused inverting snaps leave no inverted element: the only admissible failure
/// is a singular system from a piece held by fewer than three non-collinear fixed nodes.
inline ::testing::AssertionResult admissible(const interactive::AugmentedCutStepReport& r) {
  if (r.free_components != 0)
    return ::testing::AssertionFailure() << r.free_components << " free components";
  if (r.inverted_elements != 0)
    return ::testing::AssertionFailure() << r.inverted_elements << " inverted elements";
  if (r.ok() || (r.status == interactive::CutSolveStatus::kSolverFailed &&
                 r.solve.status == linalg::AugmentedStatus::kSingularModifiedSystem))
    return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << r.brief();
}

}  // namespace incise::test
