#include <incise/core/error.hpp>
#include <incise/core/flop_count.hpp>
#include <incise/fem/elastic_problem.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

namespace incise::fem {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

using Mat34 = Eigen::Matrix<double, 3, 4>;
using Mat12 = Eigen::Matrix<double, 12, 12>;
using L4 = Lanes4;

/// Visits the m elements: blocks of four through `block(k)` (SIMD lanes), falling back to
/// `element(e)` for the four elements of a block that reports failure (some lane inverted), and
/// `element(e)` for the tail. Both return false for an inverted element; a block must not
/// produce side effects before it knows it succeeds. Returns false when an element is inverted.
template <class BlockFn, class ElementFn>
bool for_each_element(Index m, BlockFn&& block, ElementFn&& element) {
  const Index nb = m / 4;
  for (Index k = 0; k < nb; ++k)
    if (!block(k))
      for (Index e = 4 * k; e < 4 * k + 4; ++e)
        if (!element(e)) return false;
  for (Index e = 4 * nb; e < m; ++e)
    if (!element(e)) return false;
  return true;
}

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
      ok = K::forces_and_tangent(p, zi, b, Counted(ref.volume), x, q, k) && ok;
      out.force_and_tangent = s.flops();
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
  blocks_.resize(static_cast<std::size_t>(num_full_blocks()));
  for (Index k = 0; k < num_full_blocks(); ++k) {
    RefBlock& blk = blocks_[static_cast<std::size_t>(k)];
    for (int l = 0; l < 4; ++l) {
      const TetReference& r = refs_[static_cast<std::size_t>(4 * k + l)];
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

double ElasticProblem::add_traction_on_plane(int axis, double value, const Vec3& traction,
                                             double tolerance) {
  INCISE_CHECK(axis >= 0 && axis < 3, "add_traction_on_plane: axis must be 0, 1 or 2");
  INCISE_CHECK(traction.allFinite(), "add_traction_on_plane: traction must be finite");
  // Faces with all three vertices on the plane; a face shared by two tetrahedra is interior.
  std::map<std::array<Index, 3>, int> faces;
  static constexpr int kFaceOfTet[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  auto on_plane = [&](Index v) { return std::abs(points_(axis, v) - value) <= tolerance; };
  for (Index e = 0; e < num_elements(); ++e)
    for (const auto& f : kFaceOfTet) {
      std::array<Index, 3> tri{cells_(f[0], e), cells_(f[1], e), cells_(f[2], e)};
      if (!on_plane(tri[0]) || !on_plane(tri[1]) || !on_plane(tri[2])) continue;
      std::sort(tri.begin(), tri.end());
      ++faces[tri];
    }
  double total = 0.0;
  for (const auto& [tri, count] : faces) {
    if (count != 1) continue;
    const Vec3 x0 = points_.col(tri[0]);
    const double area = 0.5 * (points_.col(tri[1]) - x0).cross(points_.col(tri[2]) - x0).norm();
    total += area;
    for (Index v : tri) f_ext_.segment<3>(3 * v) += (area / 3.0) * traction;
  }
  return total;
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

void ElasticProblem::gather(const VecX& u, Index e, Mat34& x) const {
  for (int a = 0; a < 4; ++a) x.col(a) = u.segment<3>(3 * cells_(a, e));
}

void ElasticProblem::gather_block(const VecX& u, Index block, Mat34T<L4>& x) const {
  const Index e = 4 * block;
  for (int a = 0; a < 4; ++a) {
    const Index n0 = 3 * cells_(a, e), n1 = 3 * cells_(a, e + 1), n2 = 3 * cells_(a, e + 2),
                n3 = 3 * cells_(a, e + 3);
    for (int i = 0; i < 3; ++i) x(i, a) = L4(u[n0 + i], u[n1 + i], u[n2 + i], u[n3 + i]);
  }
}

EvalStatus ElasticProblem::energy(const VecX& u, double& energy) {
  INCISE_CHECK(u.size() == size(), "energy: u has the wrong size");
  const material::Lame p = material_.lame();
  double sum = 0.0;
  bool inverted = false;
  material::visit_model(material_.model_index(), [&](auto m) {
    using K = TetKernel<decltype(m), double>;
    using K4 = TetKernel<decltype(m), L4>;
    inverted = !for_each_element(
        num_elements(),
        [&](Index k) {
          Mat34T<L4> x;
          gather_block(u, k, x);
          const RefBlock& rb = blocks_[static_cast<std::size_t>(k)];
          L4 w;
          if (!K4::energy(p, rb.z_inv, rb.volume, x, w)) return false;
          sum += (w[0] + w[1]) + (w[2] + w[3]);
          return true;
        },
        [&](Index e) {
          Mat34 x;
          gather(u, e, x);
          const TetReference& r = refs_[static_cast<std::size_t>(e)];
          double w = 0.0;
          if (!K::energy(p, r.z_inv, r.volume, x, w)) return false;
          sum += w;
          return true;
        });
  });
  flops_ += element_flops_.energy * static_cast<std::uint64_t>(num_elements());
  if (inverted) {
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
  bool inverted = false;
  material::visit_model(material_.model_index(), [&](auto m) {
    using K = TetKernel<decltype(m), double>;
    using K4 = TetKernel<decltype(m), L4>;
    inverted = !for_each_element(
        num_elements(),
        [&](Index k) {
          Mat34T<L4> x, q;
          gather_block(u, k, x);
          const RefBlock& rb = blocks_[static_cast<std::size_t>(k)];
          if (!K4::forces(p, rb.z_inv, rb.b, x, q)) return false;
          for (int l = 0; l < 4; ++l)
            for (int a = 0; a < 4; ++a) {
              const Index n = 3 * cells_(a, 4 * k + l);
              for (int i = 0; i < 3; ++i) f_int[n + i] += q(i, a)[l];
            }
          return true;
        },
        [&](Index e) {
          Mat34 x, q;
          gather(u, e, x);
          const TetReference& r = refs_[static_cast<std::size_t>(e)];
          if (!K::forces(p, r.z_inv, r.b, x, q)) return false;
          for (int a = 0; a < 4; ++a) f_int.segment<3>(3 * cells_(a, e)) += q.col(a);
          return true;
        });
  });
  flops_ += (element_flops_.force + 12) * static_cast<std::uint64_t>(num_elements());
  if (inverted) {
    f_int.setZero();
    return EvalStatus::kInverted;
  }
  return f_int.allFinite() ? EvalStatus::kOk : EvalStatus::kNonFinite;
}

EvalStatus ElasticProblem::gradient(const VecX& u, VecX& g, double* energy_out) {
  EvalStatus s = internal_forces(u, g);
  if (s == EvalStatus::kInverted) {
    if (energy_out) *energy_out = kInf;
    return s;
  }
  g -= f_ext_;
  if (energy_out) {
    const EvalStatus se = energy(u, *energy_out);
    if (se != EvalStatus::kOk) {
      if (se == EvalStatus::kInverted) g.setZero();
      return se;
    }
  }
  return s;
}

EvalStatus ElasticProblem::hessian_product(const VecX& u, const VecX& d, VecX& out) {
  INCISE_CHECK(u.size() == size() && d.size() == size(), "hessian_product: wrong sizes");
  const material::Lame p = material_.lame();
  out.setZero(size());
  bool inverted = false;
  material::visit_model(material_.model_index(), [&](auto m) {
    using K = TetKernel<decltype(m), double>;
    using K4 = TetKernel<decltype(m), L4>;
    inverted = !for_each_element(
        num_elements(),
        [&](Index k) {
          Mat34T<L4> x, dx, dq;
          gather_block(u, k, x);
          gather_block(d, k, dx);
          const RefBlock& rb = blocks_[static_cast<std::size_t>(k)];
          if (!K4::product(p, rb.z_inv, rb.b, x, dx, dq)) return false;
          for (int l = 0; l < 4; ++l)
            for (int a = 0; a < 4; ++a) {
              const Index n = 3 * cells_(a, 4 * k + l);
              for (int i = 0; i < 3; ++i) out[n + i] += dq(i, a)[l];
            }
          return true;
        },
        [&](Index e) {
          Mat34 x, dx, dq;
          gather(u, e, x);
          gather(d, e, dx);
          const TetReference& r = refs_[static_cast<std::size_t>(e)];
          if (!K::product(p, r.z_inv, r.b, x, dx, dq)) return false;
          for (int a = 0; a < 4; ++a) out.segment<3>(3 * cells_(a, e)) += dq.col(a);
          return true;
        });
  });
  flops_ += (element_flops_.product + 12) * static_cast<std::uint64_t>(num_elements());
  if (inverted) {
    out.setZero();
    return EvalStatus::kInverted;
  }
  return out.allFinite() ? EvalStatus::kOk : EvalStatus::kNonFinite;
}

bool ElasticProblem::hessian_diagonal(const VecX& u, VecX& diag) {
  INCISE_CHECK(u.size() == size(), "hessian_diagonal: u has the wrong size");
  const material::Lame p = material_.lame();
  diag.setZero(size());
  bool inverted = false;
  material::visit_model(material_.model_index(), [&](auto m) {
    using K = TetKernel<decltype(m), double>;
    Mat34 x, q;
    Mat12 k;
    for (Index e = 0; e < num_elements(); ++e) {
      gather(u, e, x);
      const TetReference& r = refs_[static_cast<std::size_t>(e)];
      if (!K::forces_and_tangent(p, r.z_inv, r.b, r.volume, x, q, k)) {
        inverted = true;
        break;
      }
      for (int a = 0; a < 4; ++a)
        for (int i = 0; i < 3; ++i) diag[3 * cells_(a, e) + i] += k(3 * a + i, 3 * a + i);
    }
  });
  flops_ += (element_flops_.force_and_tangent + 12) * static_cast<std::uint64_t>(num_elements());
  if (inverted) return false;
  for (Eigen::Index i = 0; i < diag.size(); ++i)
    if (fixed_[static_cast<std::size_t>(i)]) diag[i] = 1.0;
  return diag.allFinite();
}

void ElasticProblem::build_pattern() {
  const Eigen::Index n = size();
  // Column-wise sorted row lists from the element DOF pairs.
  std::vector<std::vector<int>> cols(static_cast<std::size_t>(n));
  for (Index e = 0; e < num_elements(); ++e)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
            cols[static_cast<std::size_t>(3 * cells_(b, e) + j)].push_back(3 * cells_(a, e) + i);
  for (Eigen::Index c = 0; c < n; ++c) {
    auto& v = cols[static_cast<std::size_t>(c)];
    v.push_back(static_cast<int>(c));  // the diagonal always exists
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
  }
  k_.resize(n, n);
  Eigen::VectorXi nnz_per_col(n);
  for (Eigen::Index c = 0; c < n; ++c)
    nnz_per_col[c] = static_cast<int>(cols[static_cast<std::size_t>(c)].size());
  k_.reserve(nnz_per_col);
  for (Eigen::Index c = 0; c < n; ++c)
    for (int r : cols[static_cast<std::size_t>(c)]) k_.insert(r, c) = 0.0;
  k_.makeCompressed();
  const int* outer = k_.outerIndexPtr();
  const int* inner = k_.innerIndexPtr();
  auto find = [&](int r, int c) {
    const int* lo = inner + outer[c];
    const int* hi = inner + outer[c + 1];
    return static_cast<int>(std::lower_bound(lo, hi, r) - inner);
  };
  // Per element and node pair (a, b) and column j of the 3×3 block: the value index of entry
  // (3a, 3b + j). Rows 3a+1 and 3a+2 follow contiguously (CSC, sorted rows, and every element
  // couples all three DOFs of its nodes), so one index serves three values.
  scatter_.resize(static_cast<std::size_t>(num_elements()) * kScatterPerElement);
  for (Index e = 0; e < num_elements(); ++e)
    for (int b = 0; b < 4; ++b)
      for (int j = 0; j < 3; ++j)
        for (int a = 0; a < 4; ++a)
          scatter_[static_cast<std::size_t>(e) * kScatterPerElement +
                   static_cast<std::size_t>((3 * b + j) * 4 + a)] =
              find(3 * cells_(a, e), 3 * cells_(b, e) + j);
  diag_.resize(static_cast<std::size_t>(n));
  for (Eigen::Index c = 0; c < n; ++c)
    diag_[static_cast<std::size_t>(c)] = find(static_cast<int>(c), static_cast<int>(c));
}

EvalStatus ElasticProblem::assemble_tangent(const VecX& u, FixedDofTreatment treatment) {
  INCISE_CHECK(u.size() == size(), "assemble_tangent: u has the wrong size");
  if (scatter_.empty() && num_elements() > 0) build_pattern();
  if (k_.rows() != size()) build_pattern();
  double* val = k_.valuePtr();
  std::fill(val, val + k_.nonZeros(), 0.0);
  const material::Lame p = material_.lame();
  bool inverted = false;
  const auto scatter = [&](Index e, const auto& entry) {
    const int* s = scatter_.data() + static_cast<std::size_t>(e) * kScatterPerElement;
    for (int c = 0; c < 12; ++c)
      for (int a = 0; a < 4; ++a) {
        double* dst = val + s[4 * c + a];
        dst[0] += entry(3 * a, c);
        dst[1] += entry(3 * a + 1, c);
        dst[2] += entry(3 * a + 2, c);
      }
  };
  material::visit_model(material_.model_index(), [&](auto m) {
    using K = TetKernel<decltype(m), double>;
    using K4 = TetKernel<decltype(m), L4>;
    Mat12T<L4> k4;
    Mat12 k;
    inverted = !for_each_element(
        num_elements(),
        [&](Index blk) {
          Mat34T<L4> x, q;
          gather_block(u, blk, x);
          const RefBlock& rb = blocks_[static_cast<std::size_t>(blk)];
          if (!K4::forces_and_tangent(p, rb.z_inv, rb.b, rb.volume, x, q, k4)) return false;
          // Mat12T<Lanes4> is 144 consecutive groups of 4 lane values (column-major).
          static_assert(sizeof(L4) == 4 * sizeof(double), "Lanes4 must be four packed doubles");
          const double* lanes = reinterpret_cast<const double*>(k4.data());
          for (int l = 0; l < 4; ++l)
            scatter(4 * blk + l, [&](int r, int c) { return lanes[4 * (12 * c + r) + l]; });
          return true;
        },
        [&](Index e) {
          Mat34 x, q;
          gather(u, e, x);
          const TetReference& r = refs_[static_cast<std::size_t>(e)];
          if (!K::forces_and_tangent(p, r.z_inv, r.b, r.volume, x, q, k)) return false;
          scatter(e, [&](int rr, int c) { return k(rr, c); });
          return true;
        });
  });
  flops_ += (element_flops_.force_and_tangent + 144) * static_cast<std::uint64_t>(num_elements());
  if (inverted) return EvalStatus::kInverted;
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
  for (Eigen::Index t = 0; t < k_.nonZeros(); ++t)
    if (!std::isfinite(val[t])) return EvalStatus::kNonFinite;
  return EvalStatus::kOk;
}

EvalStatus ElasticProblem::tangent(const VecX& u, Eigen::SparseMatrix<double>& k,
                                   FixedDofTreatment treatment) {
  const EvalStatus s = assemble_tangent(u, treatment);
  k = k_;
  return s;
}

}  // namespace incise::fem
