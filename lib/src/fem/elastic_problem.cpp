#include <incise/core/error.hpp>
#include <incise/core/flop_count.hpp>
#include <incise/fem/elastic_problem.hpp>
#include <incise/mesh/tet_faces.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <sstream>

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && \
    !defined(INCISE_SANITIZED_BUILD)
#include <immintrin.h>  // the AVX block gather of the assembled product (INCISE_AVX_KERNELS)
#endif

namespace incise::fem {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

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
Index chunk_elements(Index m) {
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
bool all_finite(const double* v, Eigen::Index n) {
  double s[4] = {0.0, 0.0, 0.0, 0.0};
  Eigen::Index t = 0;
  for (; t + 4 <= n; t += 4)
    for (int l = 0; l < 4; ++l) s[l] += v[t + l] - v[t + l];
  for (; t < n; ++t) s[0] += v[t] - v[t];
  return ((s[0] + s[1]) + (s[2] + s[3])) == 0.0;
}

/// g −= f and whether every entry of the result is finite, in one pass (as all_finite).
bool subtract_all_finite(VecX& g, const VecX& f) {
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

}  // namespace

ElementFlops element_flops(const material::Material& material) {
  // A generic reference tetrahedron and a generic non-inverted deformation (det F > 0): the
  // kernels' arithmetic does not depend on the values, only on the model and its parameters.
  Mat34 z;
  z << 0.1, 1.2, 0.3, -0.2, 0.2, 0.1, 1.1, -0.3, -0.1, 0.2, 0.3, 0.9;
  const TetReference ref = make_tet_reference(z);
  Mat34 xd;
  xd << 0.01, 0.03, -0.02, 0.005, -0.02, 0.04, 0.01, -0.01, 0.03, -0.01, 0.02, 0.015;
  Mat34 dd;
  dd << 0.3, -0.1, 0.2, 0.4, 0.1, 0.5, -0.3, 0.2, -0.2, 0.1, 0.6, -0.4;
  const material::Lame p = material.lame();
  return material::visit_model(material.model_index(), [&](auto m) {
    using M = decltype(m);
    using K = TetKernel<M, Counted>;
    const Mat3T<Counted> zi = ref.z_inv.cast<Counted>();
    const Mat3T<Counted> b = ref.b.cast<Counted>();
    const Mat34T<Counted> x = xd.cast<Counted>();
    const Mat34T<Counted> d = dd.cast<Counted>();
    Mat34T<Counted> q, dq;
    Mat12T<Counted> k;
    Counted w;
    ElementFlops out;
    bool ok = true;
    {
      FlopScope s;
      ok = K::energy(p, zi, Counted(ref.volume), x, w) && ok;
      out.energy = s.flops();
    }
    {
      FlopScope s;
      ok = K::forces(p, zi, b, x, q) && ok;
      out.force = s.flops();
    }
    {
      FlopScope s;
      Counted we;
      ok = K::forces_and_energy(p, zi, b, Counted(ref.volume), x, q, we) && ok;
      out.force_and_energy = s.flops();
    }
    {
      FlopScope s;
      Counted we;
      ok = K::forces_energy_and_product(p, zi, b, Counted(ref.volume), x, d, q, dq, we) && ok;
      out.force_energy_and_product = s.flops();
    }
    {
      FlopScope s;
      ok = K::forces_and_product(p, zi, b, x, d, q, dq) && ok;
      out.force_and_product = s.flops();
    }
    {
      FlopScope s;
      ok = K::product(p, zi, b, x, d, dq) && ok;
      out.product = s.flops();
    }
    {
      FlopScope s;
      Counted c;
      ok = K::curvature(p, zi, Counted(ref.volume), x, d, c) && ok;
      out.curvature = s.flops();
    }
    {
      FlopScope s;
      ok = K::forces_and_tangent(p, zi, b, Counted(ref.volume), x, q, k) && ok;
      out.force_and_tangent = s.flops();
    }
    {
      FlopScope s;
      ok = K::tangent(p, zi, b, Counted(ref.volume), x, k) && ok;
      out.tangent = s.flops();
    }
    INCISE_CHECK(ok, "flop-count deformation unexpectedly inverted");
    return out;
  });
}

std::vector<Index> nodes_on_plane(const mesh::MeshData& mesh, int axis, double value,
                                  double tolerance) {
  INCISE_CHECK(axis >= 0 && axis < 3, "axis must be 0, 1 or 2");
  std::vector<Index> out;
  for (Index i = 0; i < mesh.num_points(); ++i)
    if (std::abs(mesh.points(axis, i) - value) <= tolerance) out.push_back(i);
  return out;
}

std::vector<Index> nodes_in_box(const mesh::MeshData& mesh, const Vec3& lo, const Vec3& hi) {
  std::vector<Index> out;
  for (Index i = 0; i < mesh.num_points(); ++i) {
    const Vec3 x = mesh.points.col(i);
    if ((x.array() >= lo.array()).all() && (x.array() <= hi.array()).all()) out.push_back(i);
  }
  return out;
}

ElasticProblem::ElasticProblem(const mesh::MeshData& mesh, const material::Material& material)
    : points_(mesh.points), cells_(mesh.cells), material_(material) {
  if (mesh.dimension != 3 || mesh.cells.rows() != 4)
    throw ParameterError("ElasticProblem needs a 3D tetrahedral mesh (4 vertices per cell)");
  const Index n = mesh.num_points();
  refs_.resize(static_cast<std::size_t>(mesh.num_cells()));
  for (Index e = 0; e < mesh.num_cells(); ++e) {
    Mat34 x;
    for (int a = 0; a < 4; ++a) {
      const Index v = cells_(a, e);
      if (v < 0 || v >= n) {
        std::ostringstream os;
        os << "element " << e << " references node " << v << " outside [0, " << n << ")";
        throw ParameterError(os.str());
      }
      x.col(a) = points_.col(v);
    }
    refs_[static_cast<std::size_t>(e)] = make_tet_reference(x);
    if (!(refs_[static_cast<std::size_t>(e)].volume > 0.0)) {
      std::ostringstream os;
      os << "element " << e << " has non-positive reference volume "
         << refs_[static_cast<std::size_t>(e)].volume << " m^3 (inverted or degenerate)";
      throw ParameterError(os.str());
    }
  }
  // Sweep order: elements sorted by their smallest node index (stable counting sort, O(n + m)).
  // Consecutive elements then touch nearby entries of the node-indexed vectors and nearby
  // columns of the assembled matrix; on a 48,000-tet box with shuffled elements this restores
  // the throughput of the generator's ordered mesh (docs/fem_performance.md). Sums over
  // elements are taken in this order, which changes results by round-off only.
  const Index m = mesh.num_cells();
  {
    std::vector<Index> start(static_cast<std::size_t>(n) + 1, 0);
    const auto key = [&](Index e) { return static_cast<std::size_t>(cells_.col(e).minCoeff()); };
    for (Index e = 0; e < m; ++e) ++start[key(e) + 1];
    for (std::size_t v = 0; v < static_cast<std::size_t>(n); ++v) start[v + 1] += start[v];
    order_.resize(static_cast<std::size_t>(m));
    for (Index e = 0; e < m; ++e) order_[static_cast<std::size_t>(start[key(e)]++)] = e;
    sweep_cells_.resize(4 * static_cast<std::size_t>(m));
    for (std::size_t i = 0; i < order_.size(); ++i)
      for (int a = 0; a < 4; ++a)
        sweep_cells_[4 * i + static_cast<std::size_t>(a)] = cells_(a, order_[i]);
  }
  blocks_.resize(static_cast<std::size_t>(num_full_blocks()));
  for (Index k = 0; k < num_full_blocks(); ++k) {
    RefBlock& blk = blocks_[static_cast<std::size_t>(k)];
    for (int l = 0; l < 4; ++l) {
      const TetReference& r =
          refs_[static_cast<std::size_t>(order_[static_cast<std::size_t>(4 * k + l)])];
      for (int i = 0; i < 9; ++i) {
        blk.z_inv(i).set(l, r.z_inv(i));
        blk.b(i).set(l, r.b(i));
      }
      blk.volume.set(l, r.volume);
    }
  }
  fixed_.assign(static_cast<std::size_t>(size()), 0);
  f_ext_ = VecX::Zero(size());
  rebuild_mass();
  element_flops_ = element_flops(material_);
  threads_ = default_thread_count();
  build_schedule();
}

void ElasticProblem::build_schedule() {
  // Chunks of chunk_elements(m) consecutive sweep positions (one chunk up to 4,096 elements); the
  // resources a chunk touches are its elements' nodes (every scatter — nodal vectors, diagonal,
  // matrix entry (a, b) — goes to DOFs or DOF pairs of one element's nodes, so chunks without a
  // common node never write a common value).
  const Index m = num_elements();
  const Index chunk_ = chunk_elements(m);
  const Index nc = (m + chunk_ - 1) / chunk_;
  std::vector<Index> start(static_cast<std::size_t>(nc) + 1);
  for (Index c = 0; c <= nc; ++c) start[static_cast<std::size_t>(c)] = 4 * std::min(m, c * chunk_);
  schedule_ = make_chunk_schedule(start, sweep_cells_, num_nodes());
  free_schedule_ = ChunkSchedule{};
  free_schedule_.colour.assign(static_cast<std::size_t>(nc), 0);
  free_schedule_.order.resize(static_cast<std::size_t>(nc));
  for (Index c = 0; c < nc; ++c) free_schedule_.order[static_cast<std::size_t>(c)] = c;
  free_schedule_.pred_start.assign(static_cast<std::size_t>(nc) + 1, 0);
  free_schedule_.num_colours = nc > 0 ? 1 : 0;
}

void ElasticProblem::set_threads(int threads) {
  INCISE_CHECK_PARAM(threads >= 1 && threads <= kMaxThreads,
                     "ElasticProblem::set_threads: threads must be from 1 to 256");
  threads_ = threads;
}

void ElasticProblem::rebuild_mass() {
  mass_ = VecX::Zero(size());
  const double rho = material_.density();
  for (Index e = 0; e < num_elements(); ++e) {
    const double m4 = 0.25 * rho * refs_[static_cast<std::size_t>(e)].volume;
    for (int a = 0; a < 4; ++a) mass_.segment<3>(3 * cells_(a, e)).array() += m4;
  }
}

void ElasticProblem::fix_nodes(const std::vector<Index>& nodes) {
  for (Index v : nodes) {
    INCISE_CHECK(v >= 0 && v < num_nodes(), "fix_nodes: node index out of range");
    for (int i = 0; i < 3; ++i) fixed_[static_cast<std::size_t>(3 * v + i)] = 1;
  }
}

void ElasticProblem::fix_dof(Eigen::Index dof) {
  INCISE_CHECK(dof >= 0 && dof < size(), "fix_dof: DOF index out of range");
  fixed_[static_cast<std::size_t>(dof)] = 1;
}

void ElasticProblem::clear_constraints() {
  std::fill(fixed_.begin(), fixed_.end(), 0);
}

void ElasticProblem::add_point_load(const PointLoad& load) {
  INCISE_CHECK(load.node >= 0 && load.node < num_nodes(), "add_point_load: bad node index");
  INCISE_CHECK(load.force.allFinite(), "add_point_load: force must be finite");
  point_loads_.push_back(load);
  f_ext_.segment<3>(3 * load.node) += load.force;
}

void ElasticProblem::add_gravity(const Vec3& g) {
  INCISE_CHECK(g.allFinite(), "add_gravity: g must be finite");
  gravity_ += g;
  for (Index v = 0; v < num_nodes(); ++v)
    f_ext_.segment<3>(3 * v) += mass_.segment<3>(3 * v).cwiseProduct(g);
}

mesh::CellMatrix boundary_faces_on_plane(const Eigen::Matrix3Xd& points,
                                         const mesh::CellMatrix& tets, int axis, double value,
                                         double tolerance) {
  INCISE_CHECK(axis >= 0 && axis < 3, "boundary_faces_on_plane: axis must be 0, 1 or 2");
  const mesh::CellMatrix boundary = mesh::boundary_faces(tets);
  auto on_plane = [&](Index v) { return std::abs(points(axis, v) - value) <= tolerance; };
  std::vector<Eigen::Index> in_plane;
  for (Eigen::Index t = 0; t < boundary.cols(); ++t)
    if (on_plane(boundary(0, t)) && on_plane(boundary(1, t)) && on_plane(boundary(2, t)))
      in_plane.push_back(t);
  return boundary(Eigen::all, in_plane);
}

double add_surface_traction(const Eigen::Matrix3Xd& points, const mesh::CellMatrix& faces,
                            const Vec3& traction, VecX& f) {
  INCISE_CHECK(faces.rows() == 3, "add_surface_traction: faces need 3 vertex indices each");
  INCISE_CHECK(f.size() == 3 * points.cols(), "add_surface_traction: f needs 3 entries per point");
  INCISE_CHECK(traction.allFinite(), "add_surface_traction: traction must be finite");
  INCISE_CHECK(faces.size() == 0 || (faces.minCoeff() >= 0 && faces.maxCoeff() < points.cols()),
               "add_surface_traction: face vertex index out of range");
  double total = 0.0;
  for (Eigen::Index t = 0; t < faces.cols(); ++t) {
    const Vec3 x0 = points.col(faces(0, t));
    const double area =
        0.5 * (points.col(faces(1, t)) - x0).cross(points.col(faces(2, t)) - x0).norm();
    total += area;
    for (int k = 0; k < 3; ++k) f.segment<3>(3 * faces(k, t)) += (area / 3.0) * traction;
  }
  return total;
}

double ElasticProblem::add_traction_on_plane(int axis, double value, const Vec3& traction,
                                             double tolerance) {
  INCISE_CHECK(traction.allFinite(), "add_traction_on_plane: traction must be finite");
  return add_surface_traction(
      points_, boundary_faces_on_plane(points_, cells_, axis, value, tolerance), traction, f_ext_);
}

void ElasticProblem::clear_loads() {
  point_loads_.clear();
  gravity_.setZero();
  f_ext_.setZero();
}

void ElasticProblem::project(VecX& v) const {
  for (Eigen::Index i = 0; i < v.size(); ++i)
    if (fixed_[static_cast<std::size_t>(i)]) v[i] = 0.0;
}

double ElasticProblem::external_force_norm() const {
  double s = 0.0;
  for (Eigen::Index i = 0; i < f_ext_.size(); ++i)
    if (!fixed_[static_cast<std::size_t>(i)]) s += f_ext_[i] * f_ext_[i];
  return std::sqrt(s);
}

std::vector<Eigen::Index> ElasticProblem::free_dofs() const {
  std::vector<Eigen::Index> out;
  for (Eigen::Index i = 0; i < size(); ++i)
    if (!fixed_[static_cast<std::size_t>(i)]) out.push_back(i);
  return out;
}

double ElasticProblem::volume() const {
  double v = 0.0;
  for (const auto& r : refs_) v += r.volume;
  return v;
}

namespace {

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

bool kernel_isa_available(KernelIsa isa) {
  if (isa == KernelIsa::kBaseline) return true;
#if INCISE_AVX_KERNELS
  static const bool avx = __builtin_cpu_supports("avx") != 0;
  return avx;
#else
  return false;
#endif
}

KernelIsa best_kernel_isa() {
  return kernel_isa_available(KernelIsa::kAvx) ? KernelIsa::kAvx : KernelIsa::kBaseline;
}

const char* to_string(KernelIsa isa) {
  return isa == KernelIsa::kAvx ? "avx" : "baseline";
}

void ElasticProblem::set_kernel_isa(KernelIsa isa) {
  INCISE_CHECK_PARAM(kernel_isa_available(isa),
                     "ElasticProblem::set_kernel_isa: this build or CPU has no such kernels");
  isa_ = isa;
}

template <class Visit>
bool ElasticProblem::sweep(bool scatters, double& total, Visit&& visit) const {
  const Index m = num_elements();
  const int nc = schedule_.num_chunks();
  std::vector<double> partial(static_cast<std::size_t>(nc), 0.0);
  std::vector<char> ok(static_cast<std::size_t>(nc), 1);
  const ChunkArgs args{sweep_cells_.data(),
                       scatter_.empty() ? nullptr : scatter_.data(),
                       refs_.data(),
                       order_.data(),
                       blocks_.data(),
                       m,
                       chunk_elements(m),
                       partial.data(),
                       ok.data()};
  const ChunkSchedule& schedule = scatters ? schedule_ : free_schedule_;
#if INCISE_AVX_KERNELS
  if (isa_ == KernelIsa::kAvx) {
    run_chunks(schedule, threads_, [&](int c) { sweep_chunk_avx<RefBlock>(args, visit, c); });
  } else {
    run_chunks(schedule, threads_, [&](int c) { sweep_chunk_baseline<RefBlock>(args, visit, c); });
  }
#else
  run_chunks(schedule, threads_, [&](int c) { sweep_chunk_baseline<RefBlock>(args, visit, c); });
#endif
  total = 0.0;
  bool all_ok = true;
  for (int c = 0; c < nc; ++c) {
    total += partial[static_cast<std::size_t>(c)];
    all_ok = all_ok && ok[static_cast<std::size_t>(c)] != 0;
  }
  return all_ok;
}

EvalStatus ElasticProblem::energy(const VecX& u, double& energy) {
  INCISE_CHECK(u.size() == size(), "energy: u has the wrong size");
  const material::Lame p = material_.lame();
  double sum = 0.0;
  const bool ok = material::visit_model(material_.model_index(), [&](auto m) {
    return sweep(false, sum, [&](const auto& el, auto& w, double& part) INCISE_LAMBDA_INLINE {
      using T = typename std::decay_t<decltype(el)>::Scalar;
      el.gather(u.data(), w.x);
      T e(0);
      if (!TetKernel<decltype(m), T>::energy(p, el.z_inv(), el.volume(), w.x, e)) return false;
      part += el.sum(e);
      return true;
    });
  });
  flops_ += element_flops_.energy * static_cast<std::uint64_t>(num_elements());
  if (!ok) {
    energy = kInf;
    return EvalStatus::kInverted;
  }
  energy = sum - f_ext_.dot(u);
  return std::isfinite(energy) ? EvalStatus::kOk : EvalStatus::kNonFinite;
}

EvalStatus ElasticProblem::internal_forces(const VecX& u, VecX& f_int) {
  INCISE_CHECK(u.size() == size(), "internal_forces: u has the wrong size");
  const material::Lame p = material_.lame();
  f_int.setZero(size());
  double* out = f_int.data();
  double unused = 0.0;  // no energy in this sweep
  const bool ok = material::visit_model(material_.model_index(), [&](auto m) {
    return sweep(true, unused, [&](const auto& el, auto& w, double& /*part*/) INCISE_LAMBDA_INLINE {
      using T = typename std::decay_t<decltype(el)>::Scalar;
      el.gather(u.data(), w.x);
      if (!TetKernel<decltype(m), T>::forces(p, el.z_inv(), el.b(), w.x, w.q)) return false;
      el.add(w.q, out);
      return true;
    });
  });
  flops_ += (element_flops_.force + 12) * static_cast<std::uint64_t>(num_elements());
  if (!ok) {
    f_int.setZero();
    return EvalStatus::kInverted;
  }
  return f_int.allFinite() ? EvalStatus::kOk : EvalStatus::kNonFinite;
}

EvalStatus ElasticProblem::gradient(const VecX& u, VecX& g, double* energy_out) {
  if (!energy_out) {
    const EvalStatus s = internal_forces(u, g);
    if (s != EvalStatus::kInverted) g -= f_ext_;
    return s;
  }
  // Gradient and energy in one sweep from the same kinematics (the sums, and so the results,
  // are those of internal_forces() and energy(): same kernels, same element order).
  INCISE_CHECK(u.size() == size(), "gradient: u has the wrong size");
  const material::Lame p = material_.lame();
  g.setZero(size());
  double* out = g.data();
  double sum = 0.0;
  const bool ok = material::visit_model(material_.model_index(), [&](auto m) {
    return sweep(true, sum, [&](const auto& el, auto& w, double& part) INCISE_LAMBDA_INLINE {
      using T = typename std::decay_t<decltype(el)>::Scalar;
      el.gather(u.data(), w.x);
      T e(0);
      if (!TetKernel<decltype(m), T>::forces_and_energy(p, el.z_inv(), el.b(), el.volume(), w.x,
                                                        w.q, e))
        return false;
      el.add(w.q, out);
      part += el.sum(e);
      return true;
    });
  });
  flops_ += (element_flops_.force_and_energy + 13) * static_cast<std::uint64_t>(num_elements());
  if (!ok) {
    g.setZero();
    *energy_out = kInf;
    return EvalStatus::kInverted;
  }
  const bool finite = subtract_all_finite(g, f_ext_);  // g −= f_ext
  *energy_out = sum - f_ext_.dot(u);
  if (!std::isfinite(*energy_out)) return EvalStatus::kNonFinite;
  return finite ? EvalStatus::kOk : EvalStatus::kNonFinite;
}

EvalStatus ElasticProblem::gradient_energy_product(const VecX& u, const VecX& d, VecX& g,
                                                   double& energy, VecX& out) {
  INCISE_CHECK(u.size() == size() && d.size() == size(), "gradient_energy_product: wrong sizes");
  const material::Lame p = material_.lame();
  g.setZero(size());
  out.setZero(size());
  double* gq = g.data();
  double* dst = out.data();
  double sum = 0.0;
  const bool ok = material::visit_model(material_.model_index(), [&](auto m) {
    return sweep(true, sum, [&](const auto& el, auto& w, double& part) INCISE_LAMBDA_INLINE {
      using T = typename std::decay_t<decltype(el)>::Scalar;
      el.gather(u.data(), w.x);
      el.gather(d.data(), w.d);
      T e(0);
      if (!TetKernel<decltype(m), T>::forces_energy_and_product(p, el.z_inv(), el.b(), el.volume(),
                                                                w.x, w.d, w.q, w.dq, e))
        return false;
      el.add(w.q, gq);
      el.add(w.dq, dst);
      part += el.sum(e);
      return true;
    });
  });
  flops_ +=
      (element_flops_.force_energy_and_product + 25) * static_cast<std::uint64_t>(num_elements());
  if (!ok) {
    g.setZero();
    out.setZero();
    energy = kInf;
    return EvalStatus::kInverted;
  }
  g -= f_ext_;
  energy = sum - f_ext_.dot(u);
  if (!std::isfinite(energy)) return EvalStatus::kNonFinite;
  return g.allFinite() && out.allFinite() ? EvalStatus::kOk : EvalStatus::kNonFinite;
}

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
  return all_finite(val, k_.nonZeros()) ? EvalStatus::kOk : EvalStatus::kNonFinite;
}

EvalStatus ElasticProblem::tangent(const VecX& u, Eigen::SparseMatrix<double>& k,
                                   FixedDofTreatment treatment) {
  const EvalStatus s = assemble_tangent(u, treatment);
  k = k_;
  return s;
}

}  // namespace incise::fem
