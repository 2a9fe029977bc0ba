#include "element_sweep.hpp"

#include <incise/core/error.hpp>

#include <algorithm>
#include <cstring>

/// \file
/// ElasticProblem's tangent: the sparsity pattern and scatter map of K, its assembly by an
/// element sweep, and its diagonal.

namespace incise::fem {

using detail::kScatterStride;

template <class Sink>
bool ElasticProblem::tangent_sweep(const VecX& u, Sink&& sink) const {
  const material::Lame p = material_.lame();
  double unused = 0.0;  // no energy in this sweep
  return material::visit_model(material_.model_index(), [&](auto m) {
    return sweep(true, unused, [&](const auto& el, auto& w, double& /*part*/) INCISE_LAMBDA_INLINE {
      using T = typename std::decay_t<decltype(el)>::Scalar;
      el.gather(u.data(), w.x);
      if (!TetKernel<decltype(m), T>::tangent(p, el.z_inv(), el.b(), el.volume(), w.x, w.k))
        return false;
      sink(el, w.k);
      return true;
    });
  });
}

bool ElasticProblem::hessian_diagonal(const VecX& u, VecX& diag) {
  INCISE_CHECK(u.size() == size(), "hessian_diagonal: u has the wrong size");
  diag.setZero(size());
  if (assembled_product_) {  // K's diagonal, kept when the product's blocks were built
    if (assemble_product_matrix(u) != EvalStatus::kOk) return false;
    diag = assembled_diag_;
    for (Eigen::Index i = 0; i < diag.size(); ++i)
      if (fixed_[static_cast<std::size_t>(i)]) diag[i] = 1.0;
    return diag.allFinite();
  }
  double* dst = diag.data();
  const bool ok = tangent_sweep(
      u, [&](const auto& el, const auto& k) INCISE_LAMBDA_INLINE { el.add_diagonal(k, dst); });
  flops_ += (element_flops_.tangent + 12) * static_cast<std::uint64_t>(num_elements());
  if (!ok) return false;
  for (Eigen::Index i = 0; i < diag.size(); ++i)
    if (fixed_[static_cast<std::size_t>(i)]) diag[i] = 1.0;
  return diag.allFinite();
}

void ElasticProblem::build_pattern() {
  const Eigen::Index n = size();
  const auto nodes = static_cast<std::size_t>(num_nodes());
  const std::size_t m = order_.size();
  // Node → incident sweep positions (4·position + local index), by counting sort.
  std::vector<int> inc_start(nodes + 1, 0);
  for (std::size_t q = 0; q < 4 * m; ++q)
    ++inc_start[static_cast<std::size_t>(sweep_cells_[q]) + 1];
  for (std::size_t b = 0; b < nodes; ++b) inc_start[b + 1] += inc_start[b];
  std::vector<int> inc(4 * m);
  {
    std::vector<int> fill(inc_start.begin(), inc_start.end() - 1);
    for (std::size_t q = 0; q < 4 * m; ++q)
      inc[static_cast<std::size_t>(fill[static_cast<std::size_t>(sweep_cells_[q])]++)] =
          static_cast<int>(q);
  }
  // Node adjacency (the node itself included), each list sorted: every element couples all
  // three DOFs of its nodes, so column 3·b + j holds rows 3·a + i for every neighbour a of b
  // and i = 0, 1, 2. Neighbours are collected once each (a stamp per node), then sorted.
  std::vector<int> adj_start(nodes + 1, 0), adj;
  adj.reserve(16 * nodes);
  {
    std::vector<int> stamp(nodes, -1);
    for (std::size_t b = 0; b < nodes; ++b) {
      const auto lo = adj.size();
      adj.push_back(static_cast<int>(b));
      stamp[b] = static_cast<int>(b);
      for (int t = inc_start[b]; t < inc_start[b + 1]; ++t) {
        const Index* cell = sweep_cells_.data() + 4 * (inc[static_cast<std::size_t>(t)] / 4);
        for (int k = 0; k < 4; ++k) {
          const auto a = static_cast<std::size_t>(cell[k]);
          if (stamp[a] == static_cast<int>(b)) continue;
          stamp[a] = static_cast<int>(b);
          adj.push_back(static_cast<int>(a));
        }
      }
      std::sort(adj.begin() + static_cast<std::ptrdiff_t>(lo), adj.end());
      adj_start[b + 1] = static_cast<int>(adj.size());
    }
  }
  // The compressed column arrays, written directly.
  k_.resize(n, n);
  const Eigen::Index nnz = 9 * static_cast<Eigen::Index>(adj.size());
  k_.resizeNonZeros(nnz);
  int* outer_w = k_.outerIndexPtr();
  int* inner_w = k_.innerIndexPtr();
  int t = 0;
  for (std::size_t b = 0; b < nodes; ++b)
    for (int j = 0; j < 3; ++j) {
      outer_w[3 * b + static_cast<std::size_t>(j)] = t;
      for (int k = adj_start[b]; k < adj_start[b + 1]; ++k)
        for (int i = 0; i < 3; ++i) inner_w[t++] = 3 * adj[static_cast<std::size_t>(k)] + i;
    }
  outer_w[n] = t;
  std::fill(k_.valuePtr(), k_.valuePtr() + nnz, 0.0);
  const int* outer = k_.outerIndexPtr();
  // Scatter map, kScatterStride = 20 ints per element: s[4b + a] = value index of entry
  // (3·node_a, 3·node_b), s[16 + b] = number of stored entries in column 3·node_b. Columns
  // 3·node_b + j (j = 0, 1, 2) have identical row patterns (every element couples all three DOFs
  // of its nodes) and are consecutive, and rows 3·node_a + i (i = 0, 1, 2) are consecutive in
  // each, so entry (3·node_a + i, 3·node_b + j) is at s[4b + a] + j·s[16 + b] + i.
  // Stored in sweep order (position i: element order_[i], nodes sweep_cells_[4i..4i+3]); filled
  // node by node with the index of each neighbour in the node's sorted list (`where`).
  scatter_.resize(m * kScatterStride);
  diag_.resize(static_cast<std::size_t>(n));
  std::vector<int> where(nodes, 0);
  for (std::size_t b = 0; b < nodes; ++b) {
    for (int k = adj_start[b]; k < adj_start[b + 1]; ++k)
      where[static_cast<std::size_t>(adj[static_cast<std::size_t>(k)])] = k - adj_start[b];
    const int c = outer[3 * b];
    for (int j = 0; j < 3; ++j)
      diag_[3 * b + static_cast<std::size_t>(j)] =
          outer[3 * b + static_cast<std::size_t>(j)] + 3 * where[b] + j;
    for (int q = inc_start[b]; q < inc_start[b + 1]; ++q) {
      const auto pos = static_cast<std::size_t>(inc[static_cast<std::size_t>(q)] / 4);
      const int local = inc[static_cast<std::size_t>(q)] % 4;
      int* sc = scatter_.data() + pos * kScatterStride;
      const Index* cell = sweep_cells_.data() + 4 * pos;
      sc[16 + local] = outer[3 * b + 1] - c;
      for (int a = 0; a < 4; ++a)
        sc[4 * local + a] = c + 3 * where[static_cast<std::size_t>(cell[a])];
    }
  }
}

EvalStatus ElasticProblem::assemble_tangent(const VecX& u, FixedDofTreatment treatment) {
  INCISE_CHECK(u.size() == size(), "assemble_tangent: u has the wrong size");
  if (scatter_.empty() && num_elements() > 0) build_pattern();
  if (k_.rows() != size()) build_pattern();
  double* val = k_.valuePtr();
  std::memset(val, 0, sizeof(double) * static_cast<std::size_t>(k_.nonZeros()));  // +0.0
  const bool ok = tangent_sweep(
      u, [&](const auto& el, const auto& k) INCISE_LAMBDA_INLINE { el.add_matrix(k, val); });
  flops_ += (element_flops_.tangent + 144) * static_cast<std::uint64_t>(num_elements());
  if (!ok) return EvalStatus::kInverted;
  if (treatment == FixedDofTreatment::kIdentity) {
    const int* outer = k_.outerIndexPtr();
    const int* inner = k_.innerIndexPtr();
    for (Eigen::Index c = 0; c < size(); ++c) {
      const bool cf = fixed_[static_cast<std::size_t>(c)] != 0;
      for (int t = outer[c]; t < outer[c + 1]; ++t)
        if (cf || fixed_[static_cast<std::size_t>(inner[t])]) val[t] = 0.0;
      if (cf) val[diag_[static_cast<std::size_t>(c)]] = 1.0;
    }
  }
  return detail::all_finite(val, k_.nonZeros()) ? EvalStatus::kOk : EvalStatus::kNonFinite;
}

EvalStatus ElasticProblem::tangent(const VecX& u, Eigen::SparseMatrix<double>& k,
                                   FixedDofTreatment treatment) {
  const EvalStatus s = assemble_tangent(u, treatment);
  k = k_;
  return s;
}

}  // namespace incise::fem
