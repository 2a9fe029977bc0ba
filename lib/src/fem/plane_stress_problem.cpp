#include <incise/core/error.hpp>
#include <incise/core/flop_count.hpp>
#include <incise/fem/plane_stress_problem.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <utility>

namespace incise::fem {

namespace {

using material::PlaneStressStatus;

Eigen::Matrix<double, 2, 3> element_values(const VecX& u, const mesh::CellMatrix& cells, Index e) {
  Eigen::Matrix<double, 2, 3> x;
  for (int a = 0; a < 3; ++a)
    for (int i = 0; i < 2; ++i) x(i, a) = u(2 * cells(a, e) + i);
  return x;
}

}  // namespace

TriElementFlops tri_element_flops(const material::Material& material, const Mat2& gradient) {
  Eigen::Matrix<double, 2, 3> z;
  z << 0.1, 1.2, 0.3, -0.2, 0.2, 1.1;
  const TriReference ref = make_tri_reference(z, 0.01);
  Eigen::Matrix<double, 2, 3> xd;
  for (int a = 0; a < 3; ++a) xd.col(a) = gradient * z.col(a);
  Eigen::Matrix<double, 2, 3> dd;
  dd << 0.3, -0.1, 0.2, 0.4, 0.1, 0.5;
  const material::Lame p = material.lame();
  return material::visit_model(material.model_index(), [&](auto m) {
    using M = decltype(m);
    using K = TriKernel<M, Counted>;
    const Mat2T<Counted> zi = ref.z_inv.cast<Counted>();
    const Mat2T<Counted> b = ref.b.cast<Counted>();
    const Mat23T<Counted> x = xd.cast<Counted>();
    const Mat23T<Counted> d = dd.cast<Counted>();
    Mat23T<Counted> q, dq;
    Mat6T<Counted> k;
    Counted w;
    TriElementFlops out;
    bool ok = true;
    {
      FlopScope s;
      ok = K::energy(p, zi, Counted(ref.volume), x, w) == PlaneStressStatus::kOk && ok;
      out.energy = s.flops();
    }
    {
      FlopScope s;
      ok = K::forces(p, zi, b, x, q) == PlaneStressStatus::kOk && ok;
      out.force = s.flops();
    }
    {
      FlopScope s;
      Counted we;
      ok =
          K::forces_and_energy(p, zi, b, Counted(ref.volume), x, q, we) == PlaneStressStatus::kOk &&
          ok;
      out.force_and_energy = s.flops();
    }
    {
      FlopScope s;
      ok = K::product(p, zi, b, x, d, dq) == PlaneStressStatus::kOk && ok;
      out.product = s.flops();
    }
    {
      FlopScope s;
      ok = K::forces_and_tangent(p, zi, b, x, q, k) == PlaneStressStatus::kOk && ok;
      out.force_and_tangent = s.flops();
    }
    INCISE_CHECK(ok, "flop-count deformation: plane-stress kernel failed");
    return out;
  });
}

PlaneStressProblem::PlaneStressProblem(const mesh::MeshData& mesh,
                                       const material::Material& material, double thickness)
    : material_(material), thickness_(thickness) {
  INCISE_CHECK_PARAM(mesh.dimension == 2 && mesh.cells.rows() == 3,
                     "PlaneStressProblem needs a 2D triangle mesh");
  INCISE_CHECK_PARAM(std::isfinite(thickness) && thickness > 0.0,
                     "thickness must be finite and > 0, got " + std::to_string(thickness));
  points_ = mesh.points.topRows<2>();
  cells_ = mesh.cells;
  refs_.resize(static_cast<std::size_t>(num_elements()));
  for (Index e = 0; e < num_elements(); ++e) {
    Eigen::Matrix<double, 2, 3> x;
    for (int a = 0; a < 3; ++a) {
      const Index v = cells_(a, e);
      INCISE_CHECK_PARAM(
          v >= 0 && v < num_nodes(),
          "element " + std::to_string(e) + " references missing node " + std::to_string(v));
      x.col(a) = points_.col(v);
    }
    refs_[static_cast<std::size_t>(e)] = make_tri_reference(x, thickness_);
    INCISE_CHECK_PARAM(refs_[static_cast<std::size_t>(e)].area > 0.0,
                       "element " + std::to_string(e) + " has non-positive area");
  }
  fixed_.assign(static_cast<std::size_t>(size()), 0);
  f_ext_ = VecX::Zero(size());
  element_flops_ = tri_element_flops(material_);
  constant_tangent_ = material::visit_model(material_.model_index(),
                                            [](auto m) { return decltype(m)::kLinearGeometry; });
}

void PlaneStressProblem::fix_nodes(const std::vector<Index>& nodes) {
  for (const Index n : nodes) {
    INCISE_CHECK(n >= 0 && n < num_nodes(), "node index out of range: " + std::to_string(n));
    fixed_[static_cast<std::size_t>(2 * n)] = fixed_[static_cast<std::size_t>(2 * n + 1)] = 1;
  }
}

void PlaneStressProblem::fix_dof(Eigen::Index dof) {
  INCISE_CHECK(dof >= 0 && dof < size(), "DOF index out of range: " + std::to_string(dof));
  fixed_[static_cast<std::size_t>(dof)] = 1;
}

void PlaneStressProblem::add_point_load(Index node, const Vec2& force) {
  INCISE_CHECK(node >= 0 && node < num_nodes(), "node index out of range: " + std::to_string(node));
  memo_.valid = false;
  f_ext_.segment<2>(2 * node) += force;
}

double PlaneStressProblem::add_traction_on_line(int axis, double value, const Vec2& traction,
                                                double tolerance) {
  INCISE_CHECK(axis == 0 || axis == 1, "axis must be 0 or 1");
  INCISE_CHECK(traction.allFinite(), "traction must be finite");
  memo_.valid = false;
  // Boundary edges: edges of exactly one triangle.
  std::map<std::pair<Index, Index>, int> count;
  for (Index e = 0; e < num_elements(); ++e)
    for (int a = 0; a < 3; ++a) {
      Index v0 = cells_(a, e), v1 = cells_((a + 1) % 3, e);
      if (v0 > v1) std::swap(v0, v1);
      ++count[{v0, v1}];
    }
  double length = 0.0;
  const Vec2 t2 = traction * thickness_;  // t̃ = t·d (N/m)
  for (const auto& [edge, n] : count) {
    if (n != 1) continue;
    const Vec2 a = points_.col(edge.first), b = points_.col(edge.second);
    if (std::abs(a(axis) - value) > tolerance || std::abs(b(axis) - value) > tolerance) continue;
    const double l = (b - a).norm();
    length += l;
    f_ext_.segment<2>(2 * edge.first) += 0.5 * l * t2;
    f_ext_.segment<2>(2 * edge.second) += 0.5 * l * t2;
  }
  return length;
}

template <class Visit>
EvalStatus PlaneStressProblem::sweep(const VecX& u, Visit&& visit) {
  INCISE_CHECK(u.size() == size(), "displacement vector has the wrong size");
  outcome_ = PlaneStressOutcome{};
  return material::visit_model(material_.model_index(), [&](auto m) {
    using K = TriKernel<decltype(m), double>;
    for (Index e = 0; e < num_elements(); ++e) {
      const PlaneStressStatus s = visit(K{}, e, element_values(u, cells_, e));
      if (s != PlaneStressStatus::kOk) {
        outcome_.status = s;
        outcome_.element = e;
        outcome_.message = "element " + std::to_string(e) + ": " +
                           (s == PlaneStressStatus::kInverted
                                ? "det F ≤ 0 where the material is undefined"
                                : "the out-of-plane stretch (e₃·S·e₃ = 0) did not converge");
        return s == PlaneStressStatus::kInverted ? EvalStatus::kInverted : EvalStatus::kNonFinite;
      }
    }
    return EvalStatus::kOk;
  });
}

EvalStatus PlaneStressProblem::energy(const VecX& u, double& energy) {
  const material::Lame p = material_.lame();
  double sum = 0.0;
  const EvalStatus s = sweep(u, [&](auto k, Index e, const Eigen::Matrix<double, 2, 3>& x) {
    const TriReference& r = refs_[static_cast<std::size_t>(e)];
    double w = 0.0;
    const PlaneStressStatus st = decltype(k)::energy(p, r.z_inv, r.volume, x, w);
    sum += w;
    return st;
  });
  flops_ += element_flops_.energy * static_cast<std::uint64_t>(num_elements());
  if (s != EvalStatus::kOk) {
    energy = std::numeric_limits<double>::infinity();
    return s;
  }
  energy = sum - f_ext_.dot(u);
  return std::isfinite(energy) ? EvalStatus::kOk : EvalStatus::kNonFinite;
}

bool PlaneStressProblem::reuse_gradient(const VecX& u, VecX& g, double* energy) {
  if (!memo_.valid || memo_.u.size() != u.size() || (energy && !memo_.has_energy)) return false;
  changed_.clear();
  for (Index v = 0; v < num_nodes(); ++v)
    if (u[2 * v] != memo_.u[2 * v] || u[2 * v + 1] != memo_.u[2 * v + 1]) changed_.push_back(v);
  if (changed_.empty()) {
    g = memo_.g;
    if (energy) *energy = memo_.energy;
    return true;
  }
  if (!constant_tangent_ || !memo_.swept ||
      2 * static_cast<std::size_t>(changed_.size()) > static_cast<std::size_t>(num_nodes()))
    return false;
  if (k_blocks_.row.empty()) assemble_constant_tangent();
  // g' = g + K·Δu. K is symmetric, so node j's column of blocks is its row transposed.
  g = memo_.g;
  std::uint64_t blocks = 0;
  for (const Index j : changed_) {
    const Vec2 dj = u.segment<2>(2 * j) - memo_.u.segment<2>(2 * j);
    for (Index r = k_blocks_.row[static_cast<std::size_t>(j)];
         r < k_blocks_.row[static_cast<std::size_t>(j) + 1]; ++r, ++blocks)
      g.segment<2>(2 * k_blocks_.col[static_cast<std::size_t>(r)]).noalias() +=
          Eigen::Map<const Mat2>(&k_blocks_.values[4 * static_cast<std::size_t>(r)]).transpose() *
          dj;
  }
  // Π' = Π + Δuᵀ(g + ½K·Δu), with K·Δu = g' − g on the changed nodes.
  double de = 0.0;
  if (energy)
    for (const Index j : changed_) {
      const Vec2 dj = u.segment<2>(2 * j) - memo_.u.segment<2>(2 * j);
      de += dj.dot(0.5 * (memo_.g.segment<2>(2 * j) + g.segment<2>(2 * j)));
    }
  flops_ += 10 * blocks + 8 * static_cast<std::uint64_t>(changed_.size());
  if (!g.allFinite() || !std::isfinite(de)) return false;  // let a sweep name the failure
  memo_.u = u;
  memo_.g = g;
  memo_.swept = false;
  memo_.has_energy = energy != nullptr;
  if (energy) *energy = memo_.energy = memo_.energy + de;
  return true;
}

EvalStatus PlaneStressProblem::gradient(const VecX& u, VecX& g, double* energy) {
  INCISE_CHECK(u.size() == size(), "displacement vector has the wrong size");
  if (reuse_gradient(u, g, energy)) {
    outcome_ = PlaneStressOutcome{};
    return EvalStatus::kOk;
  }
  memo_.valid = false;
  const material::Lame p = material_.lame();
  g = -f_ext_;
  double sum = 0.0;
  // With the energy requested, one sweep evaluates both from the same kinematics.
  const EvalStatus s = sweep(u, [&](auto k, Index e, const Eigen::Matrix<double, 2, 3>& x) {
    const TriReference& r = refs_[static_cast<std::size_t>(e)];
    Eigen::Matrix<double, 2, 3> q;
    PlaneStressStatus st;
    if (energy) {
      double w = 0.0;
      st = decltype(k)::forces_and_energy(p, r.z_inv, r.b, r.volume, x, q, w);
      sum += w;
    } else {
      st = decltype(k)::forces(p, r.z_inv, r.b, x, q);
    }
    if (st == PlaneStressStatus::kOk)
      for (int a = 0; a < 3; ++a) g.segment<2>(2 * cells_(a, e)) += q.col(a);
    return st;
  });
  flops_ += ((energy ? element_flops_.force_and_energy + 1 : element_flops_.force) + 6) *
            static_cast<std::uint64_t>(num_elements());
  if (s != EvalStatus::kOk) {
    g.setZero();
    if (energy) *energy = std::numeric_limits<double>::infinity();
    return s;
  }
  if (energy) {
    *energy = sum - f_ext_.dot(u);
    flops_ += 2 * static_cast<std::uint64_t>(size());
    if (!std::isfinite(*energy)) return EvalStatus::kNonFinite;
  }
  if (!g.allFinite()) return EvalStatus::kNonFinite;
  memo_.valid = memo_.swept = true;
  memo_.has_energy = energy != nullptr;
  memo_.energy = energy ? *energy : 0.0;
  memo_.u = u;
  memo_.g = g;
  return EvalStatus::kOk;
}

void PlaneStressProblem::assemble_constant_tangent() {
  const auto nodes = static_cast<std::size_t>(num_nodes());
  // Node adjacency (each node with itself and its element neighbours), sorted per row.
  std::vector<std::vector<Index>> adjacent(nodes);
  for (Index e = 0; e < num_elements(); ++e)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        adjacent[static_cast<std::size_t>(cells_(a, e))].push_back(cells_(b, e));
  NodeBlocks k;
  k.row.assign(nodes + 1, 0);
  for (std::size_t i = 0; i < nodes; ++i) {
    std::vector<Index>& a = adjacent[i];
    std::sort(a.begin(), a.end());
    a.erase(std::unique(a.begin(), a.end()), a.end());
    k.row[i + 1] = k.row[i] + static_cast<Index>(a.size());
    k.col.insert(k.col.end(), a.begin(), a.end());
  }
  k.values.assign(4 * k.col.size(), 0.0);
  const material::Lame p = material_.lame();
  const VecX zero = VecX::Zero(size());  // K does not depend on u: evaluate the kernels at 0
  const EvalStatus s = sweep(zero, [&](auto kernel, Index e, const Eigen::Matrix<double, 2, 3>& x) {
    const TriReference& r = refs_[static_cast<std::size_t>(e)];
    Eigen::Matrix<double, 2, 3> q;
    Mat6T<double> ke;
    const PlaneStressStatus st = decltype(kernel)::forces_and_tangent(p, r.z_inv, r.b, x, q, ke);
    if (st != PlaneStressStatus::kOk) return st;
    for (int a = 0; a < 3; ++a) {
      const Index i = cells_(a, e);
      const auto first = k.col.begin() + k.row[static_cast<std::size_t>(i)];
      const auto last = k.col.begin() + k.row[static_cast<std::size_t>(i) + 1];
      for (int b = 0; b < 3; ++b) {
        const auto r_index =
            static_cast<std::size_t>(std::lower_bound(first, last, cells_(b, e)) - k.col.begin());
        double* v = &k.values[4 * r_index];
        v[0] += ke(2 * a, 2 * b);
        v[1] += ke(2 * a + 1, 2 * b);
        v[2] += ke(2 * a, 2 * b + 1);
        v[3] += ke(2 * a + 1, 2 * b + 1);
      }
    }
    return st;
  });
  // A linear-geometry model's kernels cannot fail at u = 0 (no log, no plane-stress Newton).
  INCISE_CHECK(s == EvalStatus::kOk, "constant tangent: element kernel failed at u = 0");
  flops_ += (element_flops_.force_and_tangent + 36) * static_cast<std::uint64_t>(num_elements());
  k_blocks_ = std::move(k);
}

EvalStatus PlaneStressProblem::hessian_product(const VecX& u, const VecX& d, VecX& out) {
  INCISE_CHECK(d.size() == size(), "direction vector has the wrong size");
  if (constant_tangent_) {
    INCISE_CHECK(u.size() == size(), "displacement vector has the wrong size");
    if (k_blocks_.row.empty()) assemble_constant_tangent();
    outcome_ = PlaneStressOutcome{};
    out.resize(size());
    const NodeBlocks& k = k_blocks_;
    for (Index i = 0; i < num_nodes(); ++i) {
      Vec2 o = Vec2::Zero();
      for (Index r = k.row[static_cast<std::size_t>(i)]; r < k.row[static_cast<std::size_t>(i) + 1];
           ++r)
        o.noalias() += Eigen::Map<const Mat2>(&k.values[4 * static_cast<std::size_t>(r)]) *
                       d.segment<2>(2 * k.col[static_cast<std::size_t>(r)]);
      out.segment<2>(2 * i) = o;
    }
    flops_ += 8 * static_cast<std::uint64_t>(k.col.size());
    return EvalStatus::kOk;
  }
  const material::Lame p = material_.lame();
  out = VecX::Zero(size());
  const EvalStatus s = sweep(u, [&](auto k, Index e, const Eigen::Matrix<double, 2, 3>& x) {
    const TriReference& r = refs_[static_cast<std::size_t>(e)];
    Eigen::Matrix<double, 2, 3> dq;
    const PlaneStressStatus st =
        decltype(k)::product(p, r.z_inv, r.b, x, element_values(d, cells_, e), dq);
    if (st == PlaneStressStatus::kOk)
      for (int a = 0; a < 3; ++a) out.segment<2>(2 * cells_(a, e)) += dq.col(a);
    return st;
  });
  flops_ += (element_flops_.product + 6) * static_cast<std::uint64_t>(num_elements());
  if (s != EvalStatus::kOk) out.setZero();
  return s;
}

bool PlaneStressProblem::hessian_diagonal(const VecX& u, VecX& diag) {
  const material::Lame p = material_.lame();
  diag = VecX::Zero(size());
  const EvalStatus s = sweep(u, [&](auto k, Index e, const Eigen::Matrix<double, 2, 3>& x) {
    const TriReference& r = refs_[static_cast<std::size_t>(e)];
    Eigen::Matrix<double, 2, 3> q;
    Mat6T<double> ke;
    const PlaneStressStatus st = decltype(k)::forces_and_tangent(p, r.z_inv, r.b, x, q, ke);
    if (st == PlaneStressStatus::kOk)
      for (int j = 0; j < 6; ++j) diag(2 * cells_(j / 2, e) + j % 2) += ke(j, j);
    return st;
  });
  flops_ += (element_flops_.force_and_tangent + 6) * static_cast<std::uint64_t>(num_elements());
  if (s != EvalStatus::kOk) return false;
  for (Eigen::Index i = 0; i < size(); ++i)
    if (is_fixed(i)) diag(i) = 1.0;
  return true;
}

EvalStatus PlaneStressProblem::tangent(const VecX& u, Eigen::SparseMatrix<double>& kmat) {
  const material::Lame p = material_.lame();
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(static_cast<std::size_t>(36 * num_elements() + size()));
  const EvalStatus s = sweep(u, [&](auto k, Index e, const Eigen::Matrix<double, 2, 3>& x) {
    const TriReference& r = refs_[static_cast<std::size_t>(e)];
    Eigen::Matrix<double, 2, 3> q;
    Mat6T<double> ke;
    const PlaneStressStatus st = decltype(k)::forces_and_tangent(p, r.z_inv, r.b, x, q, ke);
    if (st != PlaneStressStatus::kOk) return st;
    for (int i = 0; i < 6; ++i) {
      const Eigen::Index gi = 2 * cells_(i / 2, e) + i % 2;
      if (is_fixed(gi)) continue;
      for (int j = 0; j < 6; ++j) {
        const Eigen::Index gj = 2 * cells_(j / 2, e) + j % 2;
        if (!is_fixed(gj)) trip.emplace_back(gi, gj, ke(i, j));
      }
    }
    return st;
  });
  flops_ += (element_flops_.force_and_tangent + 36) * static_cast<std::uint64_t>(num_elements());
  for (Eigen::Index i = 0; i < size(); ++i)
    if (is_fixed(i)) trip.emplace_back(i, i, 1.0);
  kmat.resize(size(), size());
  kmat.setFromTriplets(trip.begin(), trip.end());
  return s;
}

void PlaneStressProblem::project(VecX& v) const {
  for (Eigen::Index i = 0; i < v.size(); ++i)
    if (is_fixed(i)) v(i) = 0.0;
}

double PlaneStressProblem::external_force_norm() const {
  double s = 0.0;
  for (Eigen::Index i = 0; i < size(); ++i)
    if (!is_fixed(i)) s += f_ext_(i) * f_ext_(i);
  return std::sqrt(s);
}

}  // namespace incise::fem
