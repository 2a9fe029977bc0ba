#include "element_sweep.hpp"

#include <incise/core/error.hpp>

#include <atomic>
#include <cmath>
#include <memory>

#if INCISE_AVX_KERNELS
#include <immintrin.h>  // the AVX block gather of the assembled product
#endif

/// \file
/// ElasticProblem's K(u)·d — matrix-free by an element sweep, or from K assembled once in 3×3
/// node blocks (linear geometry; assembled_hessian() for any material) — and the curvature dᵀKd.

namespace incise::fem {

using detail::kInf;

namespace {

#if INCISE_AVX_KERNELS
/// Node rows [first, last) of the assembled product K·d from full 3×3 node blocks stored as
/// padded columns (block t: c[4i + j] = K(3a + i, 3b + j), a = node[t], c[4i + 3] = 0): the
/// gather of hessian_product() with the three rows of a node in one 256-bit register — per row
/// the same products summed in the same order (no FMA), so bitwise the scalar gather's.
__attribute__((target("avx"))) void block_gather_avx(Index first, Index last, const int* start,
                                                     const int* node, const double* val4,
                                                     const double* src, double* dst) {
  for (Index b = first; b < last; ++b) {
    __m256d s = _mm256_setzero_pd();
    for (int t = start[b]; t < start[b + 1]; ++t) {
      const double* x = src + 3 * node[t];
      const double* c = val4 + 12 * t;
      __m256d p = _mm256_mul_pd(_mm256_loadu_pd(c), _mm256_broadcast_sd(x));
      p = _mm256_add_pd(p, _mm256_mul_pd(_mm256_loadu_pd(c + 4), _mm256_broadcast_sd(x + 1)));
      p = _mm256_add_pd(p, _mm256_mul_pd(_mm256_loadu_pd(c + 8), _mm256_broadcast_sd(x + 2)));
      s = _mm256_add_pd(s, p);
    }
    alignas(32) double out[4];
    _mm256_store_pd(out, s);
    dst[3 * b] = out[0];
    dst[3 * b + 1] = out[1];
    dst[3 * b + 2] = out[2];
  }
}
#endif

/// Node rows [first, last) of K·d from full 3×3 node blocks stored as rows of the gather
/// (block t: v[3j + i] = K(3a + i, 3b + j), a = node[t]): the scalar gather of
/// hessian_product().
void block_gather(Index first, Index last, const int* start, const int* node, const double* val,
                  const double* src, double* dst) {
  for (Index b = first; b < last; ++b) {
    double s0 = 0.0, s1 = 0.0, s2 = 0.0;
    for (int t = start[b]; t < start[b + 1]; ++t) {
      const double* x = src + 3 * node[t];
      const double* v = val + 9 * t;
      s0 += v[0] * x[0] + v[1] * x[1] + v[2] * x[2];
      s1 += v[3] * x[0] + v[4] * x[1] + v[5] * x[2];
      s2 += v[6] * x[0] + v[7] * x[1] + v[8] * x[2];
    }
    dst[3 * b] = s0;
    dst[3 * b + 1] = s1;
    dst[3 * b + 2] = s2;
  }
}

/// K·d for all `nodes` node rows from full node blocks (val: rows of the gather, val4: padded
/// columns for the AVX gather when `avx`), in chunks of 512 nodes on `threads` threads: every
/// entry summed in one fixed order whatever the thread count.
void full_block_product(int threads, bool avx, Index nodes, const int* start, const int* node,
                        const double* val, const double* val4, const double* src, double* dst) {
  constexpr Index kNodes = 512;
  const Index chunks = (nodes + kNodes - 1) / kNodes;
  std::atomic<Index> next{0};
  run_parallel(threads, [&] {
    for (Index k = next++; k < chunks; k = next++) {
      const Index first = k * kNodes, last = std::min(nodes, (k + 1) * kNodes);
#if INCISE_AVX_KERNELS
      if (avx) {
        block_gather_avx(first, last, start, node, val4, src, dst);
        continue;
      }
#endif
      block_gather(first, last, start, node, val, src, dst);
    }
  });
  (void)avx;
  (void)val4;
}

/// The compressed-column K of build_pattern() (every column 3b + j of node b holds whole node
/// triples 3a + i of its neighbours a, ascending) as full 3×3 node blocks: node b's blocks are
/// start[b] .. start[b + 1] − 1, block t couples node[t].
void node_block_pattern(const Eigen::SparseMatrix<double>& k, std::size_t nodes,
                        std::vector<int>& start, std::vector<int>& node) {
  const int* outer = k.outerIndexPtr();
  const int* inner = k.innerIndexPtr();
  start.assign(nodes + 1, 0);
  for (std::size_t b = 0; b < nodes; ++b)
    start[b + 1] = start[b] + (outer[3 * b + 1] - outer[3 * b]) / 3;
  node.resize(static_cast<std::size_t>(start[nodes]));
  for (std::size_t b = 0; b < nodes; ++b)
    for (int t = 0; t < start[b + 1] - start[b]; ++t)
      node[static_cast<std::size_t>(start[b] + t)] = inner[outer[3 * b] + 3 * t] / 3;
}

/// Block t = k-th block of node b of that K: stored at dst[3j + i] (rows of the gather) or, when
/// `padded`, at dst[4i + j] (columns for the AVX gather; dst[4i + 3] left as it was).
void copy_node_block(const Eigen::SparseMatrix<double>& k, std::size_t b, int t, double* dst,
                     bool padded) {
  const int* outer = k.outerIndexPtr();
  const double* val = k.valuePtr();
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i)
      dst[padded ? 4 * i + j : 3 * j + i] =
          val[outer[3 * b + static_cast<std::size_t>(j)] + 3 * t + i];
}

/// K(u) of assembled_hessian() in full node blocks: the layout of the ISA's gather.
struct FrozenBlocks {
  std::vector<int> start, node;
  std::vector<double> value;  // 9 per block (rows of the gather) or 12 (padded, AVX)
  bool avx = false;
};

}  // namespace

void ElasticProblem::set_assembled_product(bool on) {
  INCISE_CHECK(!on || material_.linear_geometry(),
               "set_assembled_product: the tangent of material '" + material_.name() +
                   "' depends on u; only a linear-geometry material has one K to assemble");
  assembled_product_ = on;
}

ElasticProblem::ProductKernel ElasticProblem::product_kernel() const {
#if INCISE_AVX_KERNELS
  if (isa_ == KernelIsa::kAvx) return ProductKernel::kFullAvx;
#endif
  return threads_ == 1 && half_stored_ ? ProductKernel::kHalf : ProductKernel::kFull;
}

EvalStatus ElasticProblem::assemble_product_matrix(const VecX& u) {
  const ProductKernel kernel = product_kernel();
  const bool need_half = kernel == ProductKernel::kHalf && half_start_.empty();
  const bool need_full = kernel == ProductKernel::kFull && block_value_.empty();
  const bool need_avx = kernel == ProductKernel::kFullAvx && block_value4_.empty();
  if (!need_half && !need_full && !need_avx) return EvalStatus::kOk;
  if (assembled_diag_.size() == 0) {
    const EvalStatus s = assemble_tangent(u, FixedDofTreatment::kKeep);
    if (s != EvalStatus::kOk) return s;
    assembled_diag_.resize(size());
    for (Eigen::Index c = 0; c < size(); ++c)
      assembled_diag_[c] = k_.valuePtr()[diag_[static_cast<std::size_t>(c)]];
  } else if (assemble_tangent(u, FixedDofTreatment::kKeep) != EvalStatus::kOk) {
    return EvalStatus::kInverted;  // another layout of K after a change of threads or ISA
  }
  // Copy K into 3×3 node blocks: build_pattern() gives the three columns of node b one row
  // pattern of whole node triples, so block k of node b (neighbour a = inner[outer[3b] + 3k] / 3)
  // holds K(3a + i, 3b + j) at value index outer[3b + j] + 3k + i.
  const int* outer = k_.outerIndexPtr();
  const int* inner = k_.innerIndexPtr();
  const auto nodes = static_cast<std::size_t>(num_nodes());
  const auto copy_block = [&](std::size_t b, int k, double* dst, bool padded) {
    copy_node_block(k_, b, k, dst, padded);
  };
  if (need_half) {
    // Half storage: node b's diagonal block first, then its blocks with neighbours a > b.
    half_start_.assign(nodes + 1, 0);
    for (std::size_t b = 0; b < nodes; ++b) {
      int upper = 0;
      for (int k = 0; k < (outer[3 * b + 1] - outer[3 * b]) / 3; ++k)
        upper += inner[outer[3 * b] + 3 * k] / 3 >= static_cast<int>(b);
      half_start_[b + 1] = half_start_[b] + upper;
    }
    half_node_.resize(static_cast<std::size_t>(half_start_[nodes]));
    half_value_.resize(9 * half_node_.size());
    for (std::size_t b = 0; b < nodes; ++b) {
      auto blk = static_cast<std::size_t>(half_start_[b]) + 1;
      for (int k = 0; k < (outer[3 * b + 1] - outer[3 * b]) / 3; ++k) {
        const int a = inner[outer[3 * b] + 3 * k] / 3;
        if (a < static_cast<int>(b)) continue;
        const std::size_t at = a == static_cast<int>(b) ? half_start_[b] : blk++;
        half_node_[at] = a;
        copy_block(b, k, half_value_.data() + 9 * at, false);
      }
    }
  }
  if ((need_full || need_avx) && block_start_.empty())
    node_block_pattern(k_, nodes, block_start_, block_node_);
  if (need_full || need_avx) {
    std::vector<double>& dst = need_avx ? block_value4_ : block_value_;
    const std::size_t stride = need_avx ? 12 : 9;
    dst.assign(stride * block_node_.size(), 0.0);
    for (std::size_t b = 0; b < nodes; ++b)
      for (int k = 0; k < block_start_[b + 1] - block_start_[b]; ++k)
        copy_block(b, k, dst.data() + stride * static_cast<std::size_t>(block_start_[b] + k),
                   need_avx);
  }
  return EvalStatus::kOk;
}

EvalStatus ElasticProblem::hessian_product(const VecX& u, const VecX& d, VecX& out) {
  INCISE_CHECK(u.size() == size() && d.size() == size(), "hessian_product: wrong sizes");
  if (assembled_product_) {
    const EvalStatus s = assemble_product_matrix(u);
    if (s != EvalStatus::kOk) return s;
    out.resize(size());
    const double* src = d.data();
    double* dst = out.data();
    const Index nodes = num_nodes();
    const ProductKernel kernel = product_kernel();
    if (kernel == ProductKernel::kHalf) {
      // One thread: the half-stored K. Node b's row sums are, in increasing neighbour order,
      // the scatters of the nodes a < b (done when a was visited, a ascending), its diagonal
      // block, and the gathers of its neighbours a > b — the order and the products of the
      // gather below, and each off-diagonal block of K is bitwise the transpose of its mirror
      // (TetKernel::tangent_impl writes K_ba = K_abᵀ; both are summed over the same elements in
      // the same order), so the result is bitwise the full product's (test
      // ElasticProblem.AssembledProductEqualsMatrixFreeForLinearMaterial), with half the matrix
      // read.
      const int* start = half_start_.data();
      const int* node = half_node_.data();
      const double* val = half_value_.data();
      out.setZero();
      for (Index b = 0; b < nodes; ++b) {
        const double* xb = src + 3 * b;
        const double x0 = xb[0], x1 = xb[1], x2 = xb[2];
        double s0 = dst[3 * b], s1 = dst[3 * b + 1], s2 = dst[3 * b + 2];
        const double* v = val + 9 * start[b];
        s0 += v[0] * x0 + v[1] * x1 + v[2] * x2;
        s1 += v[3] * x0 + v[4] * x1 + v[5] * x2;
        s2 += v[6] * x0 + v[7] * x1 + v[8] * x2;
        for (int t = start[b] + 1; t < start[b + 1]; ++t) {
          // v[3j + i] = K(3a + i, 3b + j)
          double* ya = dst + 3 * node[t];
          const double* xa = src + 3 * node[t];
          v = val + 9 * t;
          s0 += v[0] * xa[0] + v[1] * xa[1] + v[2] * xa[2];
          s1 += v[3] * xa[0] + v[4] * xa[1] + v[5] * xa[2];
          s2 += v[6] * xa[0] + v[7] * xa[1] + v[8] * xa[2];
          ya[0] += v[0] * x0 + v[3] * x1 + v[6] * x2;
          ya[1] += v[1] * x0 + v[4] * x1 + v[7] * x2;
          ya[2] += v[2] * x0 + v[5] * x1 + v[8] * x2;
        }
        dst[3 * b] = s0;
        dst[3 * b + 1] = s1;
        dst[3 * b + 2] = s2;
      }
      flops_ += 18 * static_cast<std::uint64_t>(2 * half_node_.size() - num_nodes());
      return out.allFinite() ? EvalStatus::kOk : EvalStatus::kNonFinite;
    }
    // K is symmetric: (K·d)_(3b+j) = Σ over the blocks of node b of Σ_i K(3a + i, 3b + j) d_(3a+i),
    // a gather per node, each entry summed in one fixed order whatever the thread count.
    full_block_product(threads_, kernel == ProductKernel::kFullAvx, nodes, block_start_.data(),
                       block_node_.data(), block_value_.data(), block_value4_.data(), src, dst);
    flops_ += 18 * static_cast<std::uint64_t>(block_node_.size());
    return out.allFinite() ? EvalStatus::kOk : EvalStatus::kNonFinite;
  }
  const material::Lame p = material_.lame();
  out.setZero(size());
  double* dst = out.data();
  double unused = 0.0;  // no energy in this sweep
  const bool ok = material::visit_model(material_.model_index(), [&](auto m) {
    return sweep(true, unused, [&](const auto& el, auto& w, double& /*part*/) INCISE_LAMBDA_INLINE {
      using T = typename std::decay_t<decltype(el)>::Scalar;
      // The linear model's K_e does not depend on u (TetKernel::product ignores x): no gather.
      if constexpr (!decltype(m)::kLinearGeometry) el.gather(u.data(), w.x);
      el.gather(d.data(), w.d);
      if (!TetKernel<decltype(m), T>::product(p, el.z_inv(), el.b(), w.x, w.d, w.dq)) return false;
      el.add(w.dq, dst);
      return true;
    });
  });
  flops_ += (element_flops_.product + 12) * static_cast<std::uint64_t>(num_elements());
  if (!ok) {
    out.setZero();
    return EvalStatus::kInverted;
  }
  return out.allFinite() ? EvalStatus::kOk : EvalStatus::kNonFinite;
}

EvalStatus ElasticProblem::hessian_curvature(const VecX& u, const VecX& d, double& curvature) {
  INCISE_CHECK(u.size() == size() && d.size() == size(), "hessian_curvature: wrong sizes");
  if (assembled_product_) return Problem::hessian_curvature(u, d, curvature);
  const material::Lame p = material_.lame();
  double sum = 0.0;
  const bool ok = material::visit_model(material_.model_index(), [&](auto m) {
    return sweep(false, sum, [&](const auto& el, auto& w, double& part) INCISE_LAMBDA_INLINE {
      using T = typename std::decay_t<decltype(el)>::Scalar;
      if constexpr (!decltype(m)::kLinearGeometry) el.gather(u.data(), w.x);
      el.gather(d.data(), w.d);
      T c(0);
      if (!TetKernel<decltype(m), T>::curvature(p, el.z_inv(), el.volume(), w.x, w.d, c))
        return false;
      part += el.sum(c);
      return true;
    });
  });
  flops_ += (element_flops_.curvature + 1) * static_cast<std::uint64_t>(num_elements());
  if (!ok) {
    curvature = kInf;
    return EvalStatus::kInverted;
  }
  curvature = sum;
  return std::isfinite(sum) ? EvalStatus::kOk : EvalStatus::kNonFinite;
}

std::function<EvalStatus(const VecX&, VecX&)> ElasticProblem::assembled_hessian(const VecX& u) {
  INCISE_CHECK(u.size() == size(), "assembled_hessian: u has the wrong size");
  if (assembled_product_) {  // K is assembled already (linear geometry: K does not depend on u)
    return [this, u](const VecX& d, VecX& out) { return hessian_product(u, d, out); };
  }
  if (assemble_tangent(u, FixedDofTreatment::kKeep) != EvalStatus::kOk) return {};
  auto blocks = std::make_shared<FrozenBlocks>();
  const auto nodes = static_cast<std::size_t>(num_nodes());
  node_block_pattern(k_, nodes, blocks->start, blocks->node);
#if INCISE_AVX_KERNELS
  blocks->avx = isa_ == KernelIsa::kAvx;
#endif
  const std::size_t stride = blocks->avx ? 12 : 9;
  blocks->value.assign(stride * blocks->node.size(), 0.0);
  for (std::size_t b = 0; b < nodes; ++b)
    for (int t = 0; t < blocks->start[b + 1] - blocks->start[b]; ++t)
      copy_node_block(
          k_, b, t, blocks->value.data() + stride * static_cast<std::size_t>(blocks->start[b] + t),
          blocks->avx);
  return [this, blocks](const VecX& d, VecX& out) {
    INCISE_CHECK(d.size() == size(), "assembled_hessian: d has the wrong size");
    out.resize(size());
    const double* v = blocks->value.data();
    full_block_product(threads_, blocks->avx, num_nodes(), blocks->start.data(),
                       blocks->node.data(), v, v, d.data(), out.data());
    flops_ += 18 * static_cast<std::uint64_t>(blocks->node.size());
    return out.allFinite() ? EvalStatus::kOk : EvalStatus::kNonFinite;
  };
}

}  // namespace incise::fem
