#pragma once
/// \file element_sweep.hpp
/// Private to the fem module: the element loop of ElasticProblem — the element views a kernel
/// body sees (one element, or four in SIMD lanes), the chunk loop compiled once per instruction
/// set, and ElasticProblem::sweep(), which runs it on the chunk schedule (docs/fem_performance.md).
/// Every global operation is one visit of this loop: energy and gradients in
/// elastic_problem_evaluate.cpp, K·d and the curvature in elastic_problem_products.cpp, the
/// tangent in elastic_problem_tangent.cpp.

#include <incise/fem/elastic_problem.hpp>

#include <algorithm>
#include <cstddef>
#include <limits>
#include <vector>

// The AVX variant of the element loops (sweep_chunk_avx) is built by GCC on x86-64 outside the
// sanitizer builds: it relies on everything the loop calls with Lanes4 values being inlined into
// it (INCISE_KERNEL_INLINE, INCISE_LAMBDA_INLINE), so no Lanes4 crosses a call between code
// compiled for different instruction sets (their vector ABIs differ).
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && \
    !defined(INCISE_SANITIZED_BUILD)
#define INCISE_AVX_KERNELS 1
#define INCISE_LAMBDA_INLINE __attribute__((always_inline))
#else
#define INCISE_AVX_KERNELS 0
#define INCISE_LAMBDA_INLINE
#endif

namespace incise::fem {
namespace detail {

constexpr double kInf = std::numeric_limits<double>::infinity();

using Mat34 = Eigen::Matrix<double, 3, 4>;
using Mat12 = Eigen::Matrix<double, 12, 12>;
using L4 = Lanes4;

/// Ints per element in the scatter map (ElasticProblem::build_pattern).
constexpr int kScatterStride = 20;

/// A mesh of at most this many elements is one chunk: its loops run in the plain sweep order on
/// the calling thread (a sweep of 4,096 tets takes ≈ 0.2–0.5 ms, about the cost of waking a
/// worker a few times; and the sums are those of the serial loop before issue 19, which the
/// round-off-sensitive reproductions of small meshes were recorded with, e.g.
/// Nienhuys2003Ch3.LargeDiagonalCutInTheCube's case (b), docs/fem_performance.md).
constexpr Index kSingleChunkElements = 4096;

/// Elements per chunk of a mesh of m elements (depends on m only, never on the thread count).
inline Index chunk_elements(Index m) {
  return m <= kSingleChunkElements ? std::max<Index>(m, 1) : kElementChunk;
}

/// One element (T = double) or a block of four consecutive elements in SIMD lanes (T = Lanes4)
/// as a kernel sees it: reference data, gather of nodal values, and scatter-add of element
/// results into global vectors and the assembled matrix. ElasticProblem::sweep() hands either
/// kind to one generic kernel body, so every global operation is written once for both.
template <class T>
class Elements;

/// Work arrays of the kernel calls of one sweep, constructed once per sweep and not per element:
/// default construction zero-fills Lanes4 matrices, and a 12×12 Lanes4 matrix is 4.6 kB.
template <class T>
struct Scratch {
  Mat34T<T> x, d, q, dq;  ///< nodal positions, direction, forces, K_e·d
  Mat12T<T> k;            ///< element tangent
};

/// True when every v[0..n) is finite: x − x is 0 for finite x and NaN otherwise, and NaN
/// propagates through the sums (four partial sums keep the loop vectorizable).
inline bool all_finite(const double* v, Eigen::Index n) {
  double s[4] = {0.0, 0.0, 0.0, 0.0};
  Eigen::Index t = 0;
  for (; t + 4 <= n; t += 4)
    for (int l = 0; l < 4; ++l) s[l] += v[t + l] - v[t + l];
  for (; t < n; ++t) s[0] += v[t] - v[t];
  return ((s[0] + s[1]) + (s[2] + s[3])) == 0.0;
}

/// g −= f and whether every entry of the result is finite, in one pass (as all_finite).
inline bool subtract_all_finite(VecX& g, const VecX& f) {
  const Eigen::Index n = g.size();
  double* gi = g.data();
  const double* fi = f.data();
  double s[4] = {0.0, 0.0, 0.0, 0.0};
  Eigen::Index t = 0;
  for (; t + 4 <= n; t += 4)
    for (int l = 0; l < 4; ++l) {
      gi[t + l] -= fi[t + l];
      s[l] += gi[t + l] - gi[t + l];
    }
  for (; t < n; ++t) {
    gi[t] -= fi[t];
    s[0] += gi[t] - gi[t];
  }
  return ((s[0] + s[1]) + (s[2] + s[3])) == 0.0;
}

template <>
class Elements<double> {
 public:
  using Scalar = double;
  /// `cell`: the element's 4 node indices; `scatter`: its 20 scatter-map entries (or null).
  Elements(const TetReference& r, const Index* cell, const int* scatter)
      : r_(r), cell_(cell), scatter_(scatter) {}
  const Mat3& z_inv() const { return r_.z_inv; }
  const Mat3& b() const { return r_.b; }
  const double& volume() const { return r_.volume; }
  /// x(:, a) = v(3·node_a + 0..2).
  void gather(const double* v, Mat34& x) const {
    for (int a = 0; a < 4; ++a) {
      const double* src = v + 3 * static_cast<std::ptrdiff_t>(cell_[a]);
      x(0, a) = src[0];
      x(1, a) = src[1];
      x(2, a) = src[2];
    }
  }
  /// out(3·node_a + i) += q(i, a).
  void add(const Mat34& q, double* out) const {
    for (int a = 0; a < 4; ++a) {
      double* dst = out + 3 * static_cast<std::ptrdiff_t>(cell_[a]);
      dst[0] += q(0, a);
      dst[1] += q(1, a);
      dst[2] += q(2, a);
    }
  }
  /// out(3·node_a + i) += k(3a + i, 3a + i).
  void add_diagonal(const Mat12& k, double* out) const {
    for (int a = 0; a < 4; ++a)
      for (int i = 0; i < 3; ++i)
        out[3 * static_cast<std::ptrdiff_t>(cell_[a]) + i] += k(3 * a + i, 3 * a + i);
  }
  /// Adds k into the values of the assembled matrix through the scatter map (see
  /// ElasticProblem::build_pattern: entry (3a + i, 3b + j) is at s[4b + a] + j·s[16 + b] + i).
  void add_matrix(const Mat12& k, double* val) const {
    for (int b = 0; b < 4; ++b) {
      const int len = scatter_[16 + b];
      for (int j = 0; j < 3; ++j)  // one column at a time: the four node blocks of column 3b + j
        for (int a = 0; a < 4; ++a) {
          double* dst = val + scatter_[4 * b + a] + j * len;
          dst[0] += k(3 * a, 3 * b + j);
          dst[1] += k(3 * a + 1, 3 * b + j);
          dst[2] += k(3 * a + 2, 3 * b + j);
        }
    }
  }
  /// The element's share of a global sum.
  static double sum(double w) { return w; }

 private:
  const TetReference& r_;
  const Index* cell_;
  const int* scatter_;
};

template <>
class Elements<L4> {
 public:
  using Scalar = L4;
  /// `cells`: 16 node indices, element-major (4 per lane); `scatter`: 4·20 map entries.
  Elements(const Mat3T<L4>& z_inv, const Mat3T<L4>& b, const L4& volume, const Index* cells,
           const int* scatter)
      : z_inv_(z_inv), b_(b), volume_(volume), cells_(cells), scatter_(scatter) {}
  const Mat3T<L4>& z_inv() const { return z_inv_; }
  const Mat3T<L4>& b() const { return b_; }
  const L4& volume() const { return volume_; }
  void gather(const double* v, Mat34T<L4>& x) const {
    for (int a = 0; a < 4; ++a) {
      const double* s0 = v + 3 * static_cast<std::ptrdiff_t>(cells_[a]);
      const double* s1 = v + 3 * static_cast<std::ptrdiff_t>(cells_[4 + a]);
      const double* s2 = v + 3 * static_cast<std::ptrdiff_t>(cells_[8 + a]);
      const double* s3 = v + 3 * static_cast<std::ptrdiff_t>(cells_[12 + a]);
      for (int i = 0; i < 3; ++i) x(i, a) = L4(s0[i], s1[i], s2[i], s3[i]);
    }
  }
  void add(const Mat34T<L4>& q, double* out) const {
    for (int l = 0; l < 4; ++l)
      for (int a = 0; a < 4; ++a) {
        double* dst = out + 3 * static_cast<std::ptrdiff_t>(cells_[4 * l + a]);
        dst[0] += q(0, a)[l];
        dst[1] += q(1, a)[l];
        dst[2] += q(2, a)[l];
      }
  }
  void add_diagonal(const Mat12T<L4>& k, double* out) const {
    for (int l = 0; l < 4; ++l)
      for (int a = 0; a < 4; ++a)
        for (int i = 0; i < 3; ++i)
          out[3 * static_cast<std::ptrdiff_t>(cells_[4 * l + a]) + i] += k(3 * a + i, 3 * a + i)[l];
  }
  void add_matrix(const Mat12T<L4>& k, double* val) const {
    // Mat12T<Lanes4> is 144 consecutive groups of 4 lane values (column-major).
    static_assert(sizeof(L4) == 4 * sizeof(double), "Lanes4 must be four packed doubles");
    const double* lanes = reinterpret_cast<const double*>(k.data());
    for (int l = 0; l < 4; ++l) {
      const int* s = scatter_ + kScatterStride * l;
      for (int b = 0; b < 4; ++b) {
        const int len = s[16 + b];
        for (int j = 0; j < 3; ++j)  // column-wise, as in the double view (3-6% faster)
          for (int a = 0; a < 4; ++a) {
            double* dst = val + s[4 * b + a] + j * len;
            const double* src = lanes + 4 * (12 * (3 * b + j) + 3 * a) + l;
            dst[0] += src[0];
            dst[1] += src[4];
            dst[2] += src[8];
          }
      }
    }
  }
  static double sum(const L4& w) { return (w[0] + w[1]) + (w[2] + w[3]); }

 private:
  const Mat3T<L4>& z_inv_;
  const Mat3T<L4>& b_;
  const L4& volume_;
  const Index* cells_;
  const int* scatter_;
};

/// Everything one chunk of a sweep reads and writes (ElasticProblem::sweep).
struct ChunkArgs {
  const Index* cells;
  const int* scatter;
  const TetReference* refs;
  const Index* order;
  const void* blocks;  ///< ElasticProblem::RefBlock array (private type)
  Index m;
  Index chunk;
  double* partial;
  char* ok;
};

/// One chunk of a sweep: sweep positions [c·chunk, min((c+1)·chunk, m)); whole blocks of four
/// in SIMD lanes, the tail (m mod 4, last chunk only) one by one. Forced inline into the
/// instruction-set variants below (sweep_chunk_baseline, sweep_chunk_avx), together with the
/// kernels and the visit (INCISE_SWEEP_VISIT), so each variant is compiled whole for its ISA.
template <class Block, class Visit>
INCISE_KERNEL_INLINE void sweep_chunk(const ChunkArgs& a, Visit& visit, int c) {
  Scratch<double> w1;
  Scratch<L4> w4;
  double& sum = a.partial[static_cast<std::size_t>(c)];
  const Block* blocks = static_cast<const Block*>(a.blocks);
  const Index begin = c * a.chunk;
  const Index end = std::min(a.m, begin + a.chunk);
  const Index kb = begin / 4;
  const Index ke = end / 4;
  // Position i in the sweep order (order) is element order[i].
  const auto element = [&](Index pos) INCISE_LAMBDA_INLINE {
    const std::size_t i = static_cast<std::size_t>(pos);
    return visit(Elements<double>(a.refs[static_cast<std::size_t>(a.order[i])], a.cells + 4 * i,
                                  a.scatter ? a.scatter + kScatterStride * i : nullptr),
                 w1, sum);
  };
  for (Index k = kb; k < ke; ++k) {
    const std::size_t i = static_cast<std::size_t>(k);
    const Block& rb = blocks[i];
    if (visit(Elements<L4>(rb.z_inv, rb.b, rb.volume, a.cells + 16 * i,
                           a.scatter ? a.scatter + 4 * kScatterStride * i : nullptr),
              w4, sum))
      continue;
    // Some lane is inverted: the block had no side effects; redo its elements one by one.
    for (Index e = 4 * k; e < 4 * k + 4; ++e)
      if (!element(e)) {
        a.ok[static_cast<std::size_t>(c)] = 0;
        return;
      }
  }
  for (Index e = 4 * ke; e < end; ++e)
    if (!element(e)) {
      a.ok[static_cast<std::size_t>(c)] = 0;
      return;
    }
}

template <class Block, class Visit>
void sweep_chunk_baseline(const ChunkArgs& a, Visit& visit, int c) {
  sweep_chunk<Block>(a, visit, c);
}

#if INCISE_AVX_KERNELS
/// The same chunk compiled for AVX (256-bit Lanes4 operations, no FMA: every operation and its
/// rounding are those of the baseline variant, so results are bitwise equal; test
/// ElasticProblemIsa.AvxEqualsBaselineBitwise).
template <class Block, class Visit>
__attribute__((target("avx"))) void sweep_chunk_avx(const ChunkArgs& a, Visit& visit, int c) {
  sweep_chunk<Block>(a, visit, c);
}
#endif

}  // namespace detail

template <class Visit>
bool ElasticProblem::sweep(bool scatters, double& total, Visit&& visit) const {
  const Index m = num_elements();
  const int nc = schedule_.num_chunks();
  std::vector<double> partial(static_cast<std::size_t>(nc), 0.0);
  std::vector<char> ok(static_cast<std::size_t>(nc), 1);
  const detail::ChunkArgs args{sweep_cells_.data(),
                               scatter_.empty() ? nullptr : scatter_.data(),
                               refs_.data(),
                               order_.data(),
                               blocks_.data(),
                               m,
                               detail::chunk_elements(m),
                               partial.data(),
                               ok.data()};
  const ChunkSchedule& schedule = scatters ? schedule_ : free_schedule_;
#if INCISE_AVX_KERNELS
  if (isa_ == KernelIsa::kAvx) {
    run_chunks(schedule, threads_,
               [&](int c) { detail::sweep_chunk_avx<RefBlock>(args, visit, c); });
  } else {
    run_chunks(schedule, threads_,
               [&](int c) { detail::sweep_chunk_baseline<RefBlock>(args, visit, c); });
  }
#else
  run_chunks(schedule, threads_,
             [&](int c) { detail::sweep_chunk_baseline<RefBlock>(args, visit, c); });
#endif
  total = 0.0;
  bool all_ok = true;
  for (int c = 0; c < nc; ++c) {
    total += partial[static_cast<std::size_t>(c)];
    all_ok = all_ok && ok[static_cast<std::size_t>(c)] != 0;
  }
  return all_ok;
}

}  // namespace incise::fem
