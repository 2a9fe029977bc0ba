#include "element_sweep.hpp"

#include <incise/core/error.hpp>
#include <incise/core/flop_count.hpp>
#include <incise/fem/elastic_problem.hpp>
#include <incise/mesh/tet_faces.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>

/// \file
/// ElasticProblem: construction (reference data, sweep order, chunk schedule), loads,
/// constraints and the counted flops per element. The evaluations are in
/// elastic_problem_evaluate.cpp, elastic_problem_products.cpp and elastic_problem_tangent.cpp.

namespace incise::fem {

using detail::chunk_elements;
using detail::Mat34;

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

}  // namespace incise::fem
