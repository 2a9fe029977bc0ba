#pragma once
/// \file yeung2016_experiment.hpp
/// Driver of the experiments of Yeung, Crouch & Pothen 2016, §4.3 on the beam meshes of §4.2
/// item (1) (5×5×h nodes, anchored at one end), the 1×1×2 bricks of item (2) and an irregular
/// organ mesh (the liver of reference_data, standing in for the bunny of item (3)):
/// (1) deformation of an intact mesh by
/// constraining one more node per step (Fig. 5, 6); (2) an advancing planar cut that
/// duplicates one node per step, with opposing forces pulling the cut faces apart (Fig. 7, 9).
/// Per step it records the augmented update (time, m, GMRES iterations, closure sizes, §3.3 /
/// Fig. 4, 11a) and, beside it, a full refactorization + solve of the modified system with
/// CHOLMOD (the exact reference, Fig. 11b) and optionally Jacobi-PCG (solver::linear_cg).
///
/// Element matrices: the fem module's linear-elastic tetrahedron tangent
/// (fem::TetKernel<material::LinearElastic>), E = 10 kPa, ν = 0.3 unless changed.
/// Shared by verification/papers/yeung2016 (small sizes, asserted) and
/// benchmarks/linalg/augmented_bench.cpp (--table mode, the paper's sizes).

#include <incise/core/timer.hpp>
#include <incise/fem/tet_kernels.hpp>
#include <incise/io/read_mesh.hpp>
#include <incise/linalg/augmented_system.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/solver/linear_cg.hpp>

#include <time.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <string>
#include <vector>

namespace incise::yeung2016 {

/// Which §4.3 experiment.
enum class Kind { kDeform, kCut };

/// Which §4.2 mesh.
enum class Geometry {
  kBeam,   ///< mesh::make_beam(h, spacing): 5×5×h nodes (item 1)
  kBrick,  ///< mesh::make_brick(brick_n): 1×1×2 m, (n+1)²(2n+1) nodes (item 2)
  kFile    ///< a tetrahedral mesh file (the liver), lowest 10% in z anchored
};

/// Parameters of one run.
struct Options {
  Kind kind = Kind::kDeform;
  int h = 64;             ///< nodes along the beam (paper: 4 … 1024)
  int steps = 16;         ///< update steps
  double spacing = 0.01;  ///< grid spacing (m)
  double youngs = 1e4;    ///< E (Pa)
  double poisson = 0.3;   ///< ν
  linalg::SchurPreconditioner preconditioner = linalg::SchurPreconditioner::kDiagonal;
  linalg::CholmodKind cholmod = linalg::CholmodKind::kSimplicialLdl;
  bool exact = true;                 ///< refactor + solve beside every step
  int pcg_every = 0;                 ///< Jacobi-PCG on every k-th step (0: never)
  double pcg_seconds = 10;           ///< time budget of one PCG solve
  bool background_refactor = false;  ///< §3.6: keep a background refactorization running
  linalg::CholmodOrdering ordering = linalg::CholmodOrdering::kMetis;  ///< of K⁰ (augmented)
  Geometry geometry = Geometry::kBeam;
  int brick_n = 8;           ///< brick resolution (kBrick)
  std::string mesh_file;     ///< kFile: path of the mesh
  double mesh_scale = 1e-3;  ///< kFile: file units → m (the liver is in mm)
  /// Deformation only: also time the best refactorization when the sparsity pattern is kept
  /// (constrained rows/columns zeroed with a unit diagonal, symbolic analysis of K⁰ reused:
  /// numerical factorization + solve only).
  bool numeric_refactor = true;
  /// CHOLMOD kind of the reference refactorization (its ordering is CHOLMOD's default). On
  /// the thin beams simplicial is faster; on bricks and organ meshes supernodal (BLAS) is.
  linalg::CholmodKind reference_kind = linalg::CholmodKind::kSimplicialLdl;
  /// Eq. 17 by GMRES (the paper) or by the cached explicit Schur matrix.
  linalg::SchurSolver schur_solver = linalg::SchurSolver::kGmres;
  /// Threads of step 3's full backward substitution (AugmentedOptions::solve_threads).
  int solve_threads = 1;
  /// GMRES tolerance on the relative residual of eq. 17.
  double gmres_tolerance = 1e-12;
};

/// One row of the per-step table.
struct Row {
  int step = 0;
  int n = 0, m = 0;
  int gmres_iterations = 0;
  int schur_solves = 0;  ///< SchurSolver::kDirectCached: restricted solves updating H R⁻¹ J
  int closure_f = 0, closure_y = 0, closure_ja2 = 0, closure_step3 = 0;
  double t_changes = 0;  ///< applying the K changes / constraints (s)
  double t_solve = 0;    ///< AugmentedSystem::solve (s)
  double t_step1 = 0, t_step2 = 0, t_step3 = 0, t_setup = 0;
  /// Analyze + factorize of the modified system (s); forming the reduced matrix is not
  /// included (the CPU time cpu_refactor excludes it too), so speed-ups are conservative.
  double t_refactor = 0;
  double t_refactor_solve = 0;     ///< triangular solves of the refactored system (s)
  double t_numeric_refactor = -1;  ///< wall s of factorize + solve with a kept pattern (−1: n/a)
  double cpu_numeric_refactor = -1;  ///< CPU s of factorize + solve with a kept pattern (−1: n/a)
  double t_pcg = -1;                 ///< Jacobi-PCG (s), −1 when not run
  double cpu_pcg = -1;               ///< process CPU time of the Jacobi-PCG solve (s)
  double cpu_update = 0;             ///< process CPU time of changes + solve (s)
  double cpu_refactor = 0;           ///< process CPU time of refactorization + solve (s)
  long pcg_iterations = 0;
  bool pcg_converged = false;
  double rel_error = -1;  ///< ‖a_aug − a_exact‖/‖a_exact‖ (−1 when not compared)
  double ref_rcond = -1;  ///< CHOLMOD's rcond (min/max pivot) of the refactored system (−1: n/a)
  double rel_residual = -1;  ///< backward error ‖K a − f − r‖/(‖K‖₁‖a‖ + ‖f + r‖)
  bool swapped = false;      ///< background factor swapped in at this step
  std::string status;
};

/// Summary of the setup.
struct Info {
  std::string name;    ///< e.g. "beam 5x5x1024"
  double spacing = 0;  ///< characteristic edge length s (m)
  int nodes = 0, elements = 0, n0 = 0;
  long long nnz_k = 0, nnz_l = 0;
  double t_assemble = 0, t_initial_factor = 0;
};

namespace detail {

/// Process CPU time (s): on a loaded machine wall time overstates single-threaded cost.
inline double cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

inline Eigen::Matrix<double, 12, 12> element_tangent(const material::Lame& lame,
                                                     const Eigen::Matrix<double, 3, 4>& x) {
  const fem::TetReference ref = fem::make_tet_reference(x);
  Eigen::Matrix<double, 3, 4> u = Eigen::Matrix<double, 3, 4>::Zero();
  Eigen::Matrix<double, 3, 4> q;
  Eigen::Matrix<double, 12, 12> k;
  (void)fem::TetKernel<material::LinearElastic, double>::forces_and_tangent(lame, ref.z_inv, ref.b,
                                                                            ref.volume, u, q, k);
  return 0.5 * (k + k.transpose());
}

/// Beam state: tetrahedra, node → DOF map (fixed end removed), element matrices.
struct Beam {
  Eigen::Matrix3Xd points;
  std::vector<std::array<int, 4>> tets;
  std::vector<int> node_dof;
  int num_dofs = 0;
  material::Lame lame;

  std::array<int, 12> dofs(int e) const {
    std::array<int, 12> d{};
    for (int a = 0; a < 4; ++a)
      for (int i = 0; i < 3; ++i) {
        const int b = node_dof[tets[e][a]];
        d[3 * a + i] = b < 0 ? -1 : b + i;
      }
    return d;
  }
  Eigen::Matrix<double, 12, 12> ke(int e) const {
    Eigen::Matrix<double, 3, 4> x;
    for (int a = 0; a < 4; ++a) x.col(a) = points.col(tets[e][a]);
    return element_tangent(lame, x);
  }
  linalg::SparseMatrix assemble() const {
    std::vector<Eigen::Triplet<double>> t;
    t.reserve(tets.size() * 144);
    for (int e = 0; e < static_cast<int>(tets.size()); ++e) {
      const auto d = dofs(e);
      const auto k = ke(e);
      for (int a = 0; a < 12; ++a)
        for (int b = 0; b < 12; ++b)
          if (d[a] >= 0 && d[b] >= 0) t.emplace_back(d[a], d[b], k(a, b));
    }
    linalg::SparseMatrix k(num_dofs, num_dofs);
    k.setFromTriplets(t.begin(), t.end());
    k.makeCompressed();
    return k;
  }
};

/// The Beam of `mesh` with every node above `z_anchor` free (3 DOFs each, numbered in node
/// order) and the nodes at or below it anchored, i.e. removed from K⁰.
inline Beam anchored_beam(const mesh::MeshData& mesh, const material::Lame& lame, double z_anchor) {
  Beam beam;
  beam.lame = lame;
  beam.points = mesh.points;
  for (Index e = 0; e < mesh.num_cells(); ++e)
    beam.tets.push_back({mesh.cells(0, e), mesh.cells(1, e), mesh.cells(2, e), mesh.cells(3, e)});
  beam.node_dof.assign(static_cast<size_t>(mesh.num_points()), -1);
  for (Index v = 0; v < mesh.num_points(); ++v) {
    if (mesh.points(2, v) > z_anchor) {
      beam.node_dof[v] = beam.num_dofs;
      beam.num_dofs += 3;
    }
  }
  return beam;
}

/// Jacobi-PCG problem on a reduced SPD matrix (solver::linear_cg needs an incise::Problem).
class MatrixProblem : public Problem {
 public:
  MatrixProblem(const linalg::SparseMatrix& k, const Eigen::VectorXd& f) : k_(k), f_(f) {}
  Eigen::Index size() const override { return f_.size(); }
  EvalStatus energy(const VecX& u, double& e) override {
    e = 0.5 * u.dot(k_ * u) - f_.dot(u);
    return EvalStatus::kOk;
  }
  EvalStatus gradient(const VecX& u, VecX& g, double* e) override {
    g = k_ * u - f_;
    if (e) *e = 0.5 * u.dot(g - f_);
    return EvalStatus::kOk;
  }
  EvalStatus hessian_product(const VecX&, const VecX& d, VecX& out) override {
    out = k_ * d;
    return EvalStatus::kOk;
  }
  bool hessian_diagonal(const VecX&, VecX& diag) override {
    diag = k_.diagonal();
    return true;
  }
  void project(VecX&) const override {}
  bool is_fixed(Eigen::Index) const override { return false; }
  double external_force_norm() const override { return f_.norm(); }

 private:
  const linalg::SparseMatrix& k_;
  Eigen::VectorXd f_;
};

}  // namespace detail

/// Runs the experiment; rows are appended per step (row 0: the initial solve).
inline std::vector<Row> run(const Options& opt, Info& info) {
  using namespace incise::solver;
  using namespace incise::linalg;
  std::vector<Row> rows;
  material::Parameters par;
  par.youngs_modulus = opt.youngs;
  par.poisson_ratio = opt.poisson;
  const material::Material mat("linear", par);
  mesh::MeshData mesh;
  double s_len = opt.spacing;  // characteristic spacing s
  if (opt.geometry == Geometry::kBeam) {
    mesh = mesh::make_beam(opt.h, opt.spacing);
    info.name = "beam 5x5x" + std::to_string(opt.h);
  } else if (opt.geometry == Geometry::kBrick) {
    mesh = mesh::make_brick(opt.brick_n);
    s_len = 1.0 / opt.brick_n;
    info.name = "brick 1x1x2 n=" + std::to_string(opt.brick_n);
  } else {
    io::ReadOptions ro;
    ro.scale = opt.mesh_scale;
    mesh = io::read_mesh(opt.mesh_file, ro).mesh;
    double sum = 0;
    for (Index e = 0; e < mesh.num_cells(); ++e)
      for (int a = 0; a < 4; ++a)
        for (int b = a + 1; b < 4; ++b)
          sum += (mesh.points.col(mesh.cells(a, e)) - mesh.points.col(mesh.cells(b, e))).norm();
    s_len = sum / (6.0 * std::max<Index>(mesh.num_cells(), 1));
    info.name = opt.mesh_file.substr(opt.mesh_file.find_last_of('/') + 1);
  }
  info.spacing = s_len;
  const bool structured = opt.geometry != Geometry::kFile;
  const double zmin = mesh.points.row(2).minCoeff();
  const double zrange = mesh.points.row(2).maxCoeff() - zmin;
  // Anchored (removed from K⁰): the z = zmin face, or the lowest 10% of an irregular mesh.
  const double z_anchor = structured ? zmin + 1e-9 * s_len : zmin + 0.1 * zrange;
  detail::Beam beam = detail::anchored_beam(mesh, mat.lame(), z_anchor);
  info.nodes = mesh.num_points();
  info.elements = mesh.num_cells();
  Timer t;
  const SparseMatrix k0 = beam.assemble();
  info.t_assemble = t.seconds();
  info.n0 = beam.num_dofs;
  info.nnz_k = k0.nonZeros();

  AugmentedOptions aopt;
  aopt.preconditioner = opt.preconditioner;
  aopt.schur_solver = opt.schur_solver;
  aopt.solve_threads = opt.solve_threads;
  aopt.cholmod.kind = opt.cholmod;
  aopt.cholmod.ordering = opt.ordering;
  aopt.gmres.tolerance = opt.gmres_tolerance;
  aopt.gmres.restart = 200;
  aopt.gmres.max_iterations = 2000;
  AugmentedSystem aug(aopt);
  t.restart();
  if (aug.initialize(k0) != FactorStatus::kOk) return rows;
  info.t_initial_factor = t.seconds();

  const double zmax = mesh.points.row(2).maxCoeff();
  const double ymax = mesh.points.row(1).maxCoeff();
  const double xmid = 0.5 * (mesh.points.row(0).maxCoeff() + mesh.points.row(0).minCoeff());
  const double tol = 1e-6 * s_len;
  // Irregular meshes: the "top face" is the top 15% in y, the cut "plane" the nodes within s/2
  // of x = xmid, the pulled "end face" the top 10% in z.
  const double y_band = structured ? tol : 0.15 * (ymax - mesh.points.row(1).minCoeff());
  const double x_band = structured ? tol : 0.5 * s_len;
  const double z_band = structured ? tol : 0.1 * zrange;
  std::map<int, double> dirichlet;
  Eigen::VectorXd f = Eigen::VectorXd::Zero(beam.num_dofs);
  std::vector<int> order;  // nodes to constrain or to cut, in step order
  if (opt.kind == Kind::kDeform) {
    // Top surface nodes from the free end backwards: pressed down by 0.1 spacing (§4.3.1).
    for (Index v = 0; v < mesh.num_points(); ++v)
      if (ymax - mesh.points(1, v) < y_band && beam.node_dof[v] >= 0) order.push_back(v);
    std::sort(order.begin(), order.end(), [&](int a, int b) {
      if (std::abs(mesh.points(2, a) - mesh.points(2, b)) > tol)
        return mesh.points(2, a) > mesh.points(2, b);
      return mesh.points(0, a) < mesh.points(0, b);
    });
  } else {
    // Planar cut x = xmid advancing from the free end (§4.3.2); opposing forces on the end face.
    for (Index v = 0; v < mesh.num_points(); ++v) {
      if (std::abs(mesh.points(0, v) - xmid) < x_band && beam.node_dof[v] >= 0) order.push_back(v);
      if (zmax - mesh.points(2, v) < z_band && std::abs(mesh.points(0, v) - xmid) > x_band &&
          beam.node_dof[v] >= 0)
        f(beam.node_dof[v]) = mesh.points(0, v) < xmid ? -1e-3 : 1e-3;
    }
    std::sort(order.begin(), order.end(), [&](int a, int b) {
      if (std::abs(mesh.points(2, a) - mesh.points(2, b)) > tol)
        return mesh.points(2, a) > mesh.points(2, b);
      return mesh.points(1, a) > mesh.points(1, b);
    });
  }
  bool refactor_started = false;
  // Deformation: the best refactorization keeps the pattern of K⁰ (constrained rows/columns
  // zeroed, unit diagonal), so CHOLMOD's symbolic analysis is done once, outside the timing.
  CholmodFactor numeric_factor({opt.reference_kind, CholmodOrdering::kDefault});
  const bool numeric = opt.exact && opt.numeric_refactor && opt.kind == Kind::kDeform;
  if (numeric && numeric_factor.analyze(k0, 1) != FactorStatus::kOk) return rows;
  // Elements around each node (what a simulator keeps in its mesh connectivity), so that a
  // cut step's changes cost O(star) rather than a scan of all elements.
  std::vector<std::vector<int>> star(static_cast<size_t>(beam.points.cols()));
  for (int e = 0; e < static_cast<int>(beam.tets.size()); ++e)
    for (int v : beam.tets[static_cast<size_t>(e)]) star[static_cast<size_t>(v)].push_back(e);
  auto centroid_x = [&](int e) {
    double cx = 0;
    for (int b = 0; b < 4; ++b) cx += 0.25 * beam.points(0, beam.tets[static_cast<size_t>(e)][b]);
    return cx;
  };
  // A cut node is duplicated only when elements on both sides of the plane meet at it
  // (otherwise one copy would have no stiffness); on the grids every plane node qualifies.
  auto splits = [&](int v) {
    if (opt.kind != Kind::kCut) return true;
    bool left = false, right = false;
    for (int e : star[static_cast<size_t>(v)]) (centroid_x(e) > xmid ? right : left) = true;
    return left && right;
  };
  size_t next = 0;
  for (int step = 0; step <= opt.steps; ++step) {
    Row row;
    row.step = step;
    if (step > 0) {
      while (next < order.size() && !splits(order[next])) ++next;
      if (next == order.size()) break;
    }
    Timer tc;
    const double cpu0 = detail::cpu_seconds();
    if (step > 0) {
      const int p = order[next++];
      if (opt.kind == Kind::kDeform) {
        const double d[3] = {0.0, -0.1 * s_len, 0.0};
        for (int i = 0; i < 3; ++i) {
          aug.impose_dirichlet(beam.node_dof[p] + i, d[i]);
          dirichlet[beam.node_dof[p] + i] = d[i];
        }
      } else {
        const int q = static_cast<int>(beam.points.cols());
        beam.points.conservativeResize(3, q + 1);
        beam.points.col(q) = beam.points.col(p);
        const int first = aug.add_dofs(3);
        beam.node_dof.push_back(first);
        beam.num_dofs += 3;
        f.conservativeResize(beam.num_dofs);
        f.tail(3).setZero();
        star.emplace_back();
        std::vector<int> stay;
        for (int e : star[static_cast<size_t>(p)]) {
          auto& tet = beam.tets[static_cast<size_t>(e)];
          if (centroid_x(e) <= xmid) {
            stay.push_back(e);
            continue;
          }
          const int a = static_cast<int>(std::find(tet.begin(), tet.end(), p) - tet.begin());
          const auto ke = beam.ke(e);
          const auto d0 = beam.dofs(e);
          aug.add_element(std::vector<int>(d0.begin(), d0.end()), ke, -1.0);
          tet[static_cast<size_t>(a)] = q;
          const auto d1 = beam.dofs(e);
          aug.add_element(std::vector<int>(d1.begin(), d1.end()), ke, +1.0);
          star[static_cast<size_t>(q)].push_back(e);
        }
        star[static_cast<size_t>(p)] = std::move(stay);
      }
      aug.set_force(f);
    } else {
      aug.set_force(f);
    }
    row.t_changes = tc.seconds();
    if (opt.background_refactor && step >= 1 && !aug.refactorization_pending()) {
      refactor_started = aug.start_refactorization();
    }
    Eigen::VectorXd a, r;
    const AugmentedReport rep = aug.solve(a, r);
    row.cpu_update = detail::cpu_seconds() - cpu0;
    row.status = to_string(rep.status);
    row.n = rep.n;
    row.m = rep.m;
    row.gmres_iterations = rep.gmres.iterations;
    row.schur_solves = rep.schur_solves;
    row.closure_f = rep.closure_f;
    row.closure_y = rep.closure_y;
    row.closure_ja2 = rep.closure_ja2;
    row.closure_step3 = rep.closure_step3;
    row.t_solve = rep.seconds_total;
    row.t_setup = rep.seconds_setup;
    row.t_step1 = rep.seconds_step1;
    row.t_step2 = rep.seconds_step2;
    row.t_step3 = rep.seconds_step3;
    row.swapped = rep.refactorization_swapped;
    if (step == 0) info.nnz_l = rep.nnz_l;
    if (opt.exact || opt.pcg_every > 0) {
      const SparseMatrix k = aug.current_matrix();
      std::vector<bool> fixed(static_cast<size_t>(k.rows()), false);
      Eigen::VectorXd abar = Eigen::VectorXd::Zero(k.rows());
      for (const auto& [dd, v] : dirichlet) {
        fixed[dd] = true;
        abar(dd) = v;
      }
      const Eigen::VectorXd ka = k * a;
      Eigen::VectorXd res = ka - f - r;
      double k_norm = 0;  // ‖K‖₁ = max column sum
      for (int j = 0; j < k.outerSize(); ++j) {
        double c = 0;
        for (SparseMatrix::InnerIterator it(k, j); it; ++it) c += std::abs(it.value());
        k_norm = std::max(k_norm, c);
      }
      row.rel_residual = res.norm() / std::max(k_norm * a.norm() + (f + r).norm(), 1e-300);
      const ReducedMatrix red = remove_fixed_dofs(k, fixed);
      const Eigen::VectorXd rhs_full = f - k * abar;
      Eigen::VectorXd rhs(red.matrix.rows());
      for (int i = 0; i < k.rows(); ++i)
        if (red.full_to_free[i] >= 0) rhs(red.full_to_free[i]) = rhs_full(i);
      Timer tr;
      if (opt.exact) {
        CholmodFactor fac({opt.reference_kind, CholmodOrdering::kDefault});  // CHOLMOD's ordering
        const double cpu1 = detail::cpu_seconds();
        tr.restart();
        const FactorStatus fs = fac.compute(red.matrix, static_cast<std::uint64_t>(step + 1));
        row.t_refactor = tr.seconds();
        Eigen::VectorXd x;
        tr.restart();
        if (fs == FactorStatus::kOk && fac.solve(rhs, x) == FactorStatus::kOk) {
          row.t_refactor_solve = tr.seconds();
          Eigen::VectorXd ax = abar;
          for (int i = 0; i < k.rows(); ++i)
            if (red.full_to_free[i] >= 0) ax(i) = x(red.full_to_free[i]);
          row.rel_error = (a - ax).norm() / std::max(ax.norm(), 1e-300);
          row.ref_rcond = fac.rcond();
        }
        row.cpu_refactor = detail::cpu_seconds() - cpu1;
      }
      if (numeric && k.nonZeros() == k0.nonZeros()) {
        SparseMatrix kk = k;
        Eigen::VectorXd b = rhs_full;
        for (int j = 0; j < kk.outerSize(); ++j)
          for (SparseMatrix::InnerIterator it(kk, j); it; ++it)
            if (fixed[j] || fixed[it.row()]) it.valueRef() = it.row() == j ? 1.0 : 0.0;
        for (const auto& [dd, v] : dirichlet) b(dd) = v;
        const double cpu1 = detail::cpu_seconds();
        tr.restart();
        Eigen::VectorXd x;
        if (numeric_factor.factorize(kk) == FactorStatus::kOk &&
            numeric_factor.solve(b, x) == FactorStatus::kOk) {
          row.t_numeric_refactor = tr.seconds();
          row.cpu_numeric_refactor = detail::cpu_seconds() - cpu1;
        }
      }
      if (opt.pcg_every > 0 && step % opt.pcg_every == 0) {
        detail::MatrixProblem prob(red.matrix, rhs);
        LinearCgOptions copt;
        copt.preconditioner = Preconditioner::kJacobi;
        copt.stop.rule = ResidualRule::kExternalForce;
        copt.stop.epsilon = 1e-10;
        copt.budget.max_seconds = opt.pcg_seconds;
        VecX u = VecX::Zero(rhs.size());
        tr.restart();
        const double cpu1 = detail::cpu_seconds();
        const SolverReport cg = linear_cg(prob, u, copt);
        row.cpu_pcg = detail::cpu_seconds() - cpu1;
        row.t_pcg = tr.seconds();
        row.pcg_iterations = cg.iterations;
        row.pcg_converged = cg.ok();
      }
    }
    rows.push_back(row);
  }
  (void)refactor_started;
  if (aug.refactorization_pending()) (void)aug.wait_for_refactorization();
  return rows;
}

}  // namespace incise::yeung2016
