#include <incise/core/error.hpp>
#include <incise/core/parallel.hpp>
#include <incise/linalg/blas_threads.hpp>
#include <incise/linalg/dense_blas.hpp>
#include <incise/linalg/ldl_closure_solver.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <functional>
#include <iterator>
#include <utility>

namespace incise::linalg {

namespace {

// Σ a[k]·b[k] with four independent accumulators (the backward substitution is otherwise one
// serial chain of floating-point additions, latency-bound; this changes only the round-off),
// summed from the end: the backward substitution visits columns in descending order, so
// reading each column descending makes the whole pass one descending memory stream, which the
// hardware prefetcher follows (3.6× faster than ascending columns on the 25,600-node beam; SSE2
// another 4–17%).
#if defined(__SSE2__)
inline double dot(const double* a, const double* b, int len) {
  // SSE2 (baseline on x86-64): two 2-lane accumulators over pairs in descending order.
  __m128d v0 = _mm_setzero_pd(), v1 = _mm_setzero_pd();
  int k = len;
  for (; k >= 4; k -= 4) {
    v0 = _mm_add_pd(v0, _mm_mul_pd(_mm_loadu_pd(a + k - 2), _mm_loadu_pd(b + k - 2)));
    v1 = _mm_add_pd(v1, _mm_mul_pd(_mm_loadu_pd(a + k - 4), _mm_loadu_pd(b + k - 4)));
  }
  double s0 = 0;
  for (; k > 0; --k) s0 += a[k - 1] * b[k - 1];
  const __m128d v = _mm_add_pd(v0, v1);
  return s0 + (_mm_cvtsd_f64(v) + _mm_cvtsd_f64(_mm_unpackhi_pd(v, v)));
}
#else
inline double dot(const double* a, const double* b, int len) {
  double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
  int k = len;
  for (; k >= 4; k -= 4) {  // pairs in ascending address order: SIMD-friendly
    s0 += a[k - 2] * b[k - 2];
    s1 += a[k - 1] * b[k - 1];
    s2 += a[k - 4] * b[k - 4];
    s3 += a[k - 3] * b[k - 3];
  }
  for (; k > 0; --k) s0 += a[k - 1] * b[k - 1];
  return (s0 + s1) + (s2 + s3);
}
#endif

}  // namespace

ClosureLdlSolver::~ClosureLdlSolver() = default;

ClosureLdlSolver::ClosureLdlSolver(std::shared_ptr<const LdlFactorData> factor, int threads)
    : factor_(std::move(factor)) {
  INCISE_CHECK(factor_ != nullptr, "ClosureLdlSolver needs a factor");
  INCISE_CHECK(threads >= 1, "ClosureLdlSolver needs threads >= 1");
  const LdlFactorData& f = *factor_;
  work_.assign(static_cast<size_t>(f.n), 0.0);
  mark_.assign(static_cast<size_t>(f.n), 0);
  // Fundamental supernodes: column j joins the supernode of j + 1 when its pattern is exactly
  // {j + 1} ∪ pattern(j + 1) (checked entry by entry, so any factor layout is safe). Within a
  // supernode with last column j₁ and row set R = pattern(j₁), column j stores the rows
  // j+1 … j₁ first (contiguous positions), then R in the same order as column j₁.
  super_last_.resize(static_cast<size_t>(f.n));
  const int* cp = f.col_ptr.data();
  const int* ri = f.row_idx.data();
  int max_len = 0;
  for (int j = f.n - 1; j >= 0; --j) {
    const int len = cp[j + 1] - cp[j];
    bool merge = false;
    if (j + 1 < f.n && len >= 1 && ri[cp[j]] == j + 1) {
      const int len1 = cp[j + 2] - cp[j + 1];
      merge = len == len1 + 1 &&
              (len1 == 0 || std::memcmp(ri + cp[j] + 1, ri + cp[j + 1],
                                        sizeof(int) * static_cast<size_t>(len1)) == 0);
    }
    super_last_[j] = merge ? super_last_[j + 1] : j;
    if (!merge) ++num_supernodes_;
    max_len = std::max(max_len, cp[j + 1] - cp[j]);
  }
  gather_.assign(static_cast<size_t>(max_len) + 1, 0.0);
  acc_.assign(static_cast<size_t>(max_len) + 1, 0.0);
  // Row sets R of the supernodes, concatenated in ascending column order (one compact stream
  // for the backward pass instead of a scattered read of row_idx).
  super_row_ptr_.assign(static_cast<size_t>(f.n) + 1, 0);
  std::size_t total = 0;
  for (int j = 0; j < f.n; ++j) {
    if (super_last_[j] == j) total += static_cast<size_t>(cp[j + 1] - cp[j]);
  }
  super_rows_.resize(total);
  total = 0;
  for (int j = 0; j < f.n; ++j) {
    super_row_ptr_[j] = static_cast<std::int64_t>(total);
    if (super_last_[j] != j) continue;
    std::copy(ri + cp[j], ri + cp[j + 1], super_rows_.begin() + static_cast<std::ptrdiff_t>(total));
    total += static_cast<size_t>(cp[j + 1] - cp[j]);
  }
  super_row_ptr_[f.n] = static_cast<std::int64_t>(total);
  if (threads > 1) plan_threads(threads);
}

// Work split of the full backward pass. In a postordered elimination forest the subtree of
// position c is the contiguous range [c − size(c) + 1, c], and the backward substitution of a
// subtree reads x only on the subtree and its ancestors. Starting from the roots, the subtree
// with the most entries of L is repeatedly replaced by its children (its root moving to the
// serial part) while the serial part stays below a quarter of L; the frontier subtrees are
// packed into the threads largest-first, and the split with the smallest serial + busiest
// thread work is kept.
void ClosureLdlSolver::plan_threads(int threads) {
  const LdlFactorData& f = *factor_;
  const int n = f.n;
  const int* cp = f.col_ptr.data();
  std::vector<int> size(static_cast<size_t>(n), 0), first(static_cast<size_t>(n));
  std::vector<double> work(static_cast<size_t>(n), 0.0);
  std::vector<int> head(static_cast<size_t>(n), -1), next(static_cast<size_t>(n), -1);
  std::vector<int> frontier;
  for (int j = 0; j < n; ++j) first[j] = j;
  for (int j = 0; j < n; ++j) {  // children precede parents (parent > child)
    size[j] += 1;
    work[j] += 1.0 + (cp[j + 1] - cp[j]);
    const int p = f.parent[j];
    if (p < 0) {
      frontier.push_back(j);
      continue;
    }
    if (p <= j || p >= n) return;  // not an elimination forest in this ordering: stay serial
    size[p] += size[j];
    work[p] += work[j];
    first[p] = std::min(first[p], first[j]);
    next[j] = head[p];
    head[p] = j;
  }
  double total = 0;
  for (int r : frontier) total += work[r];
  for (int j = 0; j < n; ++j)
    if (size[j] != j - first[j] + 1) return;  // not postordered: stay serial
  std::vector<int> serial;
  double serial_work = 0;
  double best = total;
  std::vector<int> best_serial;
  std::vector<std::vector<std::pair<int, int>>> best_bins;
  std::vector<int> order;
  for (;;) {
    if (static_cast<int>(frontier.size()) >= threads && frontier.size() <= 4096) {
      order = frontier;
      std::sort(order.begin(), order.end(), [&](int a, int b) { return work[a] > work[b]; });
      std::vector<double> load(static_cast<size_t>(threads), 0.0);
      std::vector<std::vector<std::pair<int, int>>> bins(static_cast<size_t>(threads));
      for (int r : order) {
        const auto t =
            static_cast<size_t>(std::min_element(load.begin(), load.end()) - load.begin());
        load[t] += work[r];
        bins[t].emplace_back(first[r], r);
      }
      const double cost = serial_work + *std::max_element(load.begin(), load.end());
      if (cost < best) {
        best = cost;
        best_serial = serial;
        best_bins = std::move(bins);
        max_bin_fraction_ = *std::max_element(load.begin(), load.end()) / total;
        serial_fraction_ = serial_work / total;
      }
    }
    if (frontier.empty()) break;
    const auto it = std::max_element(frontier.begin(), frontier.end(),
                                     [&](int a, int b) { return work[a] < work[b]; });
    const int r = *it;
    const double own = 1.0 + (cp[r + 1] - cp[r]);
    if (serial_work + own > 0.25 * total) break;
    frontier.erase(it);
    serial.push_back(r);
    serial_work += own;
    for (int c = head[r]; c >= 0; c = next[c]) frontier.push_back(c);
  }
  if (best_bins.empty() || best > 0.9 * total) {  // no useful split
    serial_fraction_ = max_bin_fraction_ = 1.0;
    return;
  }
  std::sort(best_serial.begin(), best_serial.end());
  serial_ = std::move(best_serial);
  bins_ = std::move(best_bins);
  thread_gather_.assign(bins_.size() - 1, std::vector<double>(gather_.size(), 0.0));
}

std::vector<int> ClosureLdlSolver::closure(const std::vector<int>& original_indices) {
  const LdlFactorData& f = *factor_;
  if (++stamp_ == 0) {  // wrap-around: clear marks
    std::fill(mark_.begin(), mark_.end(), 0);
    stamp_ = 1;
  }
  std::vector<int> out;
  for (int i : original_indices) {
    INCISE_ASSERT(i >= 0 && i < f.n, "closure: index out of range");
    for (int p = f.inverse_perm[i]; p >= 0 && mark_[p] != stamp_; p = f.parent[p]) {
      mark_[p] = stamp_;
      out.push_back(p);
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Forward substitution (without D⁻¹) through columns j … j₁ of the supernode with last column
// j₁: x[rows] −= L(:, c) x[c] for c = j … j₁. The rows c+1 … j₁ are contiguous positions and
// are updated in place (they are the next columns' pivots); the common row set R = pattern(j₁)
// is accumulated in a contiguous buffer (one vectorizable axpy per column) and scattered into
// x[R] once per supernode instead of once per column.
inline void ClosureLdlSolver::forward_supernode(int j, int j1, double* x) {
  const LdlFactorData& f = *factor_;
  const int* cp = f.col_ptr.data();
  const int r = cp[j1 + 1] - cp[j1];
  double* acc = acc_.data();
  bool any = false;
  for (int c = j; c <= j1; ++c) {
    const double xc = x[c];
    if (xc == 0) continue;
    any = true;
    const int w = j1 - c;
    const double* v = f.values.data() + cp[c];
    double* xs = x + c + 1;
    for (int k = 0; k < w; ++k) xs[k] -= v[k] * xc;
    v += w;
    for (int k = 0; k < r; ++k) acc[k] += v[k] * xc;
  }
  if (!any) return;
  const int* rows = f.row_idx.data() + cp[j1];
  for (int k = 0; k < r; ++k) {
    x[rows[k]] -= acc[k];
    acc[k] = 0;
  }
}

// Positions sorted ascending, containing the closure of the right-hand side's structure.
// Entering a supernode at column j processes j … j₁: those of its columns that are in the
// closure follow j in the list (they are ancestors of j), and any other column holds an exact
// zero (Thm. 1) and is skipped.
template <typename Positions>
inline void ClosureLdlSolver::forward(const Positions& positions, size_t count) {
  const LdlFactorData& f = *factor_;
  double* x = work_.data();
  for (size_t t = 0; t < count;) {
    const int j = positions(t);
    const int j1 = super_last_[j];
    forward_supernode(j, j1, x);
    while (t < count && positions(t) <= j1) ++t;
  }
  for (size_t t = 0; t < count; ++t) {
    const int j = positions(t);
    x[j] /= f.d[j];
  }
}

// Backward substitution x ← L⁻ᵀ x over the positions [first, last) of `positions` taken in
// descending order (positions sorted ascending). Requires, for every processed j, that all of
// its ancestors were processed before (true for closures and for the full range). The values
// x[R] of a supernode's row set are gathered once into a contiguous buffer, so every column is
// two contiguous dot products (8 bytes of L per entry instead of 12 with the row index), and
// all of L is read as one descending stream (columns descending, each column from its end).
template <typename Positions>
inline void ClosureLdlSolver::backward(const Positions& positions, size_t count, double* gend) {
  const LdlFactorData& f = *factor_;
  const int* cp = f.col_ptr.data();
  const double* lv = f.values.data();
  double* x = work_.data();
  // Column j of a supernode with last column j₁ holds rows j+1 … j₁, then R = pattern(j₁).
  // The buffer (ending at gend) ends with x[R]; each finished x[j] is written just before the
  // part column j used, so column j − 1 finds x[j … j₁], x[R] contiguous in front of gend.
  int current = -1;
  for (size_t t = count; t-- > 0;) {
    const int j = positions(t);
    const int j1 = super_last_[j];
    if (j1 != current) {
      current = j1;
      const int r = cp[j1 + 1] - cp[j1];
      const int* rows = super_rows_.data() + super_row_ptr_[j1];
      double* gr = gend - r;
      for (int k = r; k-- > 0;) gr[k] = x[rows[k]];
      // Entering the supernode below its last column (a thread's subtree may start there):
      // its columns j+1 … j₁ were finished by the serial part.
      for (int k = j1 - j; k-- > 0;) gr[k - (j1 - j)] = x[j + 1 + k];
    }
    const int len = cp[j + 1] - cp[j];
    const double xj = x[j] - dot(lv + cp[j], gend - len, len);
    x[j] = xj;
    *(gend - len - 1) = xj;
  }
}

void ClosureLdlSolver::solve_restricted(const std::vector<int>& b_indices,
                                        const std::vector<double>& b_values,
                                        const std::vector<int>& forward_closure,
                                        const std::vector<int>& backward_closure,
                                        const std::vector<int>& wanted,
                                        std::vector<double>& x_wanted) {
  const LdlFactorData& f = *factor_;
  double* x = work_.data();
  for (size_t k = 0; k < b_indices.size(); ++k) x[f.inverse_perm[b_indices[k]]] += b_values[k];
  const int* fc = forward_closure.data();
  forward([fc](size_t t) { return fc[t]; }, forward_closure.size());
  // Entries of the forward result outside backward_closure are never read below, so only the
  // backward closure needs a consistent value: positions in it but not in the forward closure
  // hold 0, which is the exact forward result there (Thm. 1).
  const int* bc = backward_closure.data();
  backward([bc](size_t t) { return bc[t]; }, backward_closure.size(),
           gather_.data() + gather_.size());
  x_wanted.resize(wanted.size());
  for (size_t k = 0; k < wanted.size(); ++k) x_wanted[k] = x[f.inverse_perm[wanted[k]]];
  for (int j : forward_closure) x[j] = 0;
  for (int j : backward_closure) x[j] = 0;
}

void ClosureLdlSolver::solve_restricted_block(const std::vector<int>& columns,
                                              const std::vector<int>& forward_closure,
                                              const std::vector<int>& backward_closure,
                                              const std::vector<int>& wanted,
                                              Eigen::MatrixXd& x_wanted, bool dense_kernels) {
  const LdlFactorData& f = *factor_;
  const auto k = static_cast<Eigen::Index>(columns.size());
  const int kk = static_cast<int>(k);
  x_wanted.resize(static_cast<Eigen::Index>(wanted.size()), k);
  if (k == 0) return;
  if (slot_.empty()) slot_.assign(static_cast<size_t>(f.n), -1);
  // Block rows for the positions of both closures, in ascending position order (each a row of
  // k contiguous values), so that the columns of a supernode in a closure — a suffix j … j₁ —
  // are consecutive rows: the k × (j₁ − j + 1) block the dense kernels work on.
  std::vector<int> positions;
  positions.reserve(forward_closure.size() + backward_closure.size());
  std::set_union(forward_closure.begin(), forward_closure.end(), backward_closure.begin(),
                 backward_closure.end(), std::back_inserter(positions));
  for (size_t t = 0; t < positions.size(); ++t)
    slot_[static_cast<size_t>(positions[t])] = static_cast<int>(t);
  std::vector<double> y(positions.size() * static_cast<size_t>(k), 0.0);
  auto row = [&](int j) {
    return y.data() + static_cast<size_t>(slot_[static_cast<size_t>(j)]) * k;
  };
  for (Eigen::Index c = 0; c < k; ++c)
    row(f.inverse_perm[columns[static_cast<size_t>(c)]])[c] = 1.0;
  const int* cp = f.col_ptr.data();
  const int* ri = f.row_idx.data();
  const double* lv = f.values.data();
  // Supernode suffix j … j₁ (s columns) with row set R = pattern(j₁) (r rows): column c holds
  // rows c+1 … j₁ (the unit-lower triangle L_SS), then R (the block L_RS, r × s). Blocks with
  // at least kMinDenseWork multiply-adds go through dgemm/dtrsm (dense_blas.hpp) on copies of
  // L_SS and L_RS; smaller ones stay entry by entry (a BLAS call costs about as much).
  const double min_dense_work = dense_kernels ? 4096.0 : HUGE_VAL;
  std::vector<double> lss, lrs, tmp;
  auto copy_blocks = [&](int j, int j1) {
    const int s = j1 - j + 1, r = cp[j1 + 1] - cp[j1];
    lss.assign(static_cast<size_t>(s) * static_cast<size_t>(s), 0.0);
    lrs.resize(static_cast<size_t>(r) * static_cast<size_t>(s));
    for (int c = j; c <= j1; ++c) {
      const int a = c - j, w = j1 - c;
      const double* v = lv + cp[c];
      std::copy(v, v + w, lss.begin() + static_cast<std::ptrdiff_t>(a * s + a + 1));
      std::copy(v + w, v + w + r, lrs.begin() + static_cast<std::ptrdiff_t>(a) * r);
    }
  };
  const ScopedBlasThreads one_thread(1);
  last_dense_blocks_ = 0;
  // Forward: L z = b over the closure (ascending; the rows of column j are its ancestors, so in
  // the closure), then z ← D⁻¹ z.
  for (size_t t = 0; t < forward_closure.size();) {
    const int j = forward_closure[t];
    const int j1 = super_last_[j];
    while (t < forward_closure.size() && forward_closure[t] <= j1) ++t;
    const int s = j1 - j + 1, r = cp[j1 + 1] - cp[j1];
    if (static_cast<double>(k) * s * (s + r) < min_dense_work) {
      for (int c = j; c <= j1; ++c) {
        const double* zc = row(c);
        for (int p = cp[c]; p < cp[c + 1]; ++p) {
          double* zi = row(ri[p]);
          const double l = lv[p];
          for (Eigen::Index q = 0; q < k; ++q) zi[q] -= l * zc[q];
        }
      }
      continue;
    }
    copy_blocks(j, j1);
    ++last_dense_blocks_;
    double* zs = row(j);                                              // k × s, leading dimension k
    dense_trsm_right_unit_lower(true, kk, s, lss.data(), s, zs, kk);  // Zᵀ_S ← Bᵀ_S L_SS⁻ᵀ
    if (r == 0) continue;
    tmp.resize(static_cast<size_t>(r) * static_cast<size_t>(k));
    dense_gemm(false, true, kk, r, s, 1.0, zs, kk, lrs.data(), r, 0.0, tmp.data(), kk);
    const int* rows = ri + cp[j1];
    for (int i = 0; i < r; ++i) {
      double* zi = row(rows[i]);
      const double* ti = tmp.data() + static_cast<size_t>(i) * k;
      for (Eigen::Index q = 0; q < k; ++q) zi[q] -= ti[q];
    }
  }
  for (int j : forward_closure) {
    double* zj = row(j);
    const double inv = 1.0 / f.d[static_cast<size_t>(j)];
    for (Eigen::Index c = 0; c < k; ++c) zj[c] *= inv;
  }
  // Backward: Lᵀ x = z over the backward closure (descending); positions outside the forward
  // closure hold z = 0, the exact forward result there (Thm. 1).
  for (size_t t = backward_closure.size(); t > 0;) {
    const int j1 = backward_closure[t - 1];
    INCISE_ASSERT(super_last_[j1] == j1, "closure not ancestor-closed");
    size_t first = t - 1;
    while (first > 0 && super_last_[backward_closure[first - 1]] == j1) --first;
    const int j = backward_closure[first];
    t = first;
    const int s = j1 - j + 1, r = cp[j1 + 1] - cp[j1];
    if (static_cast<double>(k) * s * (s + r) < min_dense_work) {
      for (int c = j1; c >= j; --c) {
        double* xc = row(c);
        for (int p = cp[c]; p < cp[c + 1]; ++p) {
          const double* xi = row(ri[p]);
          const double l = lv[p];
          for (Eigen::Index q = 0; q < k; ++q) xc[q] -= l * xi[q];
        }
      }
      continue;
    }
    copy_blocks(j, j1);
    ++last_dense_blocks_;
    double* xs = row(j);
    if (r > 0) {
      tmp.resize(static_cast<size_t>(r) * static_cast<size_t>(k));
      const int* rows = ri + cp[j1];
      for (int i = 0; i < r; ++i)
        std::copy_n(row(rows[i]), k, tmp.data() + static_cast<size_t>(i) * k);
      dense_gemm(false, false, kk, s, r, -1.0, tmp.data(), kk, lrs.data(), r, 1.0, xs, kk);
    }
    dense_trsm_right_unit_lower(false, kk, s, lss.data(), s, xs, kk);  // Xᵀ_S ← Zᵀ_S L_SS⁻¹
  }
  for (size_t w = 0; w < wanted.size(); ++w) {
    const double* xw = row(f.inverse_perm[wanted[w]]);
    for (Eigen::Index c = 0; c < k; ++c) x_wanted(static_cast<Eigen::Index>(w), c) = xw[c];
  }
  for (int j : positions) slot_[static_cast<size_t>(j)] = -1;
}

void ClosureLdlSolver::solve_sparse_rhs(const std::vector<int>& b_indices,
                                        const std::vector<double>& b_values,
                                        const std::vector<int>& forward_closure,
                                        Eigen::VectorXd& x_out) {
  x_out.resize(factor_->n);
  solve_sparse_rhs(b_indices, b_values, forward_closure, x_out.data());
}

void ClosureLdlSolver::solve_sparse_rhs(const std::vector<int>& b_indices,
                                        const std::vector<double>& b_values,
                                        const std::vector<int>& forward_closure, double* x_out) {
  const LdlFactorData& f = *factor_;
  double* x = work_.data();
  for (size_t k = 0; k < b_indices.size(); ++k) x[f.inverse_perm[b_indices[k]]] += b_values[k];
  const int* fc = forward_closure.data();
  forward([fc](size_t t) { return fc[t]; }, forward_closure.size());
  backward_full_to(x_out);
}

void ClosureLdlSolver::backward_full_to(double* x_out) {
  const LdlFactorData& f = *factor_;
  double* x = work_.data();
  const int* perm = f.perm.data();
  if (bins_.empty()) {
    backward([](size_t t) { return static_cast<int>(t); }, static_cast<size_t>(f.n),
             gather_.data() + gather_.size());
    for (int p = 0; p < f.n; ++p) {
      x_out[perm[p]] = x[p];
      x[p] = 0;
    }
    return;
  }
  // Root side first, then the subtrees of each bin concurrently (they write disjoint
  // positions of work_ and x_out and read only their own positions and the finished root
  // side); the root side is permuted out and cleared after the join.
  const int* sp = serial_.data();
  backward([sp](size_t t) { return sp[t]; }, serial_.size(), gather_.data() + gather_.size());
  auto run_bin = [this, x, x_out, perm](size_t b, double* gend) {
    for (const auto& [lo, hi] : bins_[b]) {
      backward([lo = lo](size_t t) { return lo + static_cast<int>(t); },
               static_cast<size_t>(hi - lo + 1), gend);
      for (int p = lo; p <= hi; ++p) {
        x_out[perm[p]] = x[p];
        x[p] = 0;
      }
    }
  };
  const std::function<void(size_t)> bin = [&](size_t b) {
    std::vector<double>& g = b == 0 ? gather_ : thread_gather_[b - 1];
    run_bin(b, g.data() + g.size());
  };
  // The bins on the process's worker pool (core/parallel.hpp, persistent threads: a thread
  // created per pass started late often enough to lose about half of the gain on the measured
  // 2-vCPU machine, 2.39 vs 1.84 ms median). Each bin has its own gather buffer, so whichever
  // participant claims it, and however many run (one when the pool is busy), the result is the
  // same.
  std::atomic<size_t> next{0};
  run_parallel(static_cast<int>(bins_.size()), [&] {
    for (size_t b = next.fetch_add(1); b < bins_.size(); b = next.fetch_add(1)) bin(b);
  });
  for (int p : serial_) {
    x_out[perm[p]] = x[p];
    x[p] = 0;
  }
}

void ClosureLdlSolver::solve_dense(const Eigen::VectorXd& b, Eigen::VectorXd& x_out) {
  const LdlFactorData& f = *factor_;
  INCISE_CHECK(b.size() == f.n, "solve_dense: size mismatch");
  double* x = work_.data();
  for (int p = 0; p < f.n; ++p) x[p] = b[f.perm[p]];
  forward([](size_t t) { return static_cast<int>(t); }, static_cast<size_t>(f.n));
  x_out.resize(f.n);
  backward_full_to(x_out.data());
}

}  // namespace incise::linalg
