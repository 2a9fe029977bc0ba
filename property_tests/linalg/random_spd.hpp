#pragma once
/// \file random_spd.hpp
/// Random sparse symmetric positive definite test matrices for the linalg building blocks, and
/// the dense L of an exported LDLᵀ factor.

#include <incise/linalg/cholmod_factor.hpp>

#include <Eigen/Dense>

#include <algorithm>
#include <random>
#include <vector>

namespace incise::test {

/// A weighted graph Laplacian plus a diagonal shift: every vertex i is joined to `degree`
/// random vertices (weights in [0.5, 1.5]) of its block, and the diagonal gets a shift in
/// [shift, 2·shift]. The Laplacian is positive semidefinite, so λ_min ≥ shift and the matrix is
/// SPD; λ_max ≤ 2·(max weighted degree) + 2·shift. With `components` > 1 the vertices form that
/// many contiguous blocks without edges between them (an elimination forest). Both triangles
/// are stored, compressed.
inline linalg::SparseMatrix random_sparse_spd(int n, int degree, double shift, std::mt19937_64& rng,
                                              int components = 1) {
  std::uniform_real_distribution<double> weight(0.5, 1.5), unit(0.0, 1.0);
  std::vector<Eigen::Triplet<double>> t;
  const int block = (n + components - 1) / components;
  for (int i = 0; i < n; ++i) {
    const int lo = (i / block) * block;
    const int hi = std::min(n, lo + block) - 1;
    std::uniform_int_distribution<int> pick(lo, hi);
    t.emplace_back(i, i, shift * (1.0 + unit(rng)));
    for (int k = 0; k < degree && hi > lo; ++k) {
      int j = pick(rng);
      if (j == i) j = i == hi ? lo : i + 1;
      const double w = weight(rng);
      t.emplace_back(i, i, w);
      t.emplace_back(j, j, w);
      t.emplace_back(i, j, -w);
      t.emplace_back(j, i, -w);
    }
  }
  linalg::SparseMatrix a(n, n);
  a.setFromTriplets(t.begin(), t.end());
  a.makeCompressed();
  return a;
}

/// The unit lower-triangular L of an exported factor as a dense matrix.
inline Eigen::MatrixXd dense_l(const linalg::LdlFactorData& f) {
  Eigen::MatrixXd l = Eigen::MatrixXd::Identity(f.n, f.n);
  for (int j = 0; j < f.n; ++j)
    for (int k = f.col_ptr[j]; k < f.col_ptr[j + 1]; ++k) l(f.row_idx[k], j) = f.values[k];
  return l;
}

}  // namespace incise::test
