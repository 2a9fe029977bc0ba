/// \file augmented_equivalence_test.cpp
/// Equivalence property of the augmented-matrix method (Yeung, Crouch, Pothen 2016, §3.1–3.2):
/// after every step of a random sequence of element removals and additions (column
/// replacements, eqs. 4–6), cuts that duplicate a node and reconnect the elements on one side
/// of a plane (§4.3.2; expansion with new DOFs, eq. 12), Dirichlet impositions and releases
/// (eqs. 3, 5, 9, 11), force changes and background refactorizations (§3.6), the augmented
/// solution (displacements and reactions) equals the solution of a fresh CHOLMOD factorization
/// of the modified system. Matrices: the stand-in vector-Laplacian family of
/// augmented_stand_in.hpp on the paper's beam (5×5×h grid) and brick (1×1×2) meshes.

#include "augmented_reference.hpp"
#include "augmented_stand_in.hpp"

#include <incise/io/read_mesh.hpp>
#include <incise/mesh/generators.hpp>
#include <incise_test/seed.hpp>

#include <gtest/gtest.h>

#include <iostream>
#include <limits>
#include <map>
#include <random>
#include <string>

namespace incise::test {
namespace {

using linalg::AugmentedOptions;
using linalg::AugmentedStatus;
using linalg::AugmentedSystem;
using linalg::SchurPreconditioner;

/// Relative tolerance of the equivalence: 1e-9 (the issue's), widened to 100·eps/rcond when the
/// modified system is worse conditioned: both solutions carry a forward error ≈ κ·eps (backward
/// stable direct solves), and CHOLMOD's pivot ratio rcond is a (crude, optimistic) estimate of
/// 1/κ — hence the factor 100. GMRES runs to a relative residual 1e-14 on eq. 17: with 1e-13 the
/// Schur system's own conditioning (m ≈ n on the small brick) left errors up to 1.7e-9 (seed 2).
constexpr double kRelTol = 1e-9;
double tolerance(double rcond) {
  return std::max(kRelTol, 100 * std::numeric_limits<double>::epsilon() / rcond);
}

struct Sequence {
  CutModel model;
  AugmentedSystem aug;
  std::map<int, double> dirichlet;
  Eigen::VectorXd f;
  int steps_checked = 0;
  int cuts = 0, removals = 0, additions = 0, imposed = 0, released = 0, swaps = 0;
  int max_m = 0;
  int max_gmres_iterations = 0;
  int capacitance_columns_kept = 0;  ///< kDirectCached: columns of Φ + GΨ reused across solves

  explicit Sequence(const CutModel& m, AugmentedOptions opt) : model(m), aug(opt) {
    const linalg::FactorStatus s = aug.initialize(model.assemble());
    EXPECT_EQ(s, linalg::FactorStatus::kOk);
    f = Eigen::VectorXd::Zero(model.num_dofs);
  }

  static void remove(CutModel& m, AugmentedSystem* aug, int e) {
    if (aug) aug->add_element(m.dofs(e), m.element_matrix(e), -1.0);
    m.active[e] = 0;
  }
  static void add(CutModel& m, AugmentedSystem* aug, int e) {
    if (aug) aug->add_element(m.dofs(e), m.element_matrix(e), +1.0);
    m.active[e] = 1;
  }
  /// Node duplication (§4.3.2): elements incident to `p` whose centroid lies on the positive
  /// side of the plane through p with normal `nrm` are reconnected to a new copy p′.
  /// Returns false when the plane does not split the active star of p.
  static bool cut(CutModel& m, AugmentedSystem* aug, int p, const Eigen::Vector3d& nrm) {
    std::vector<int> moved;
    int active_star = 0, active_moved = 0;
    for (size_t e = 0; e < m.tets.size(); ++e) {
      bool inc = false;
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (int a = 0; a < 4; ++a) {
        inc = inc || m.tets[e][a] == p;
        c += 0.25 * m.points.col(m.tets[e][a]);
      }
      if (!inc) continue;
      if (m.active[e]) ++active_star;
      if ((c - m.points.col(p)).dot(nrm) > 0) {
        moved.push_back(static_cast<int>(e));
        if (m.active[e]) ++active_moved;
      }
    }
    if (active_moved == 0 || active_moved == active_star) return false;
    const int q = static_cast<int>(m.points.cols());
    m.points.conservativeResize(3, q + 1);
    m.points.col(q) = m.points.col(p);
    int first = m.num_dofs;
    if (aug) {
      first = aug->add_dofs(3);
      EXPECT_EQ(first, m.num_dofs);
    }
    m.node_dof.push_back(first);
    m.num_dofs += 3;
    for (int e : moved) {
      if (m.active[e] && aug) aug->add_element(m.dofs(e), m.element_matrix(e), -1.0);
      for (int a = 0; a < 4; ++a) {
        if (m.tets[e][a] == p) m.tets[e][a] = q;
      }
      if (m.active[e] && aug) aug->add_element(m.dofs(e), m.element_matrix(e), +1.0);
    }
    return true;
  }

  void check(const char* what) {
    if (f.size() != model.num_dofs) {
      const Eigen::Index old = f.size();
      f.conservativeResize(model.num_dofs);
      f.tail(model.num_dofs - old).setZero();
    }
    aug.set_force(f);
    Eigen::VectorXd a, r;
    const linalg::AugmentedReport rep = aug.solve(a, r);
    ASSERT_TRUE(rep.ok()) << what << ": " << linalg::to_string(rep.status) << " " << rep.message
                          << " (m=" << rep.m << ", gmres it=" << rep.gmres.iterations << ")";
    swaps += rep.refactorization_swapped ? 1 : 0;
    max_m = std::max(max_m, rep.m);
    max_gmres_iterations = std::max(max_gmres_iterations, rep.gmres.iterations);
    capacitance_columns_kept += rep.capacitance_columns_kept;
    const ReferenceSolution ref = reference_solve(model.assemble(), f, dirichlet);
    ASSERT_TRUE(ref.ok) << what;
    const double a_scale = std::max(ref.a.norm(), 1e-300);
    const double tol = tolerance(ref.rcond);
    EXPECT_LE((a - ref.a).norm(), tol * a_scale)
        << what << " step " << steps_checked << " m=" << rep.m;
    const double r_scale = std::max(ref.r.norm() + f.norm(), 1e-300);
    EXPECT_LE((r - ref.r).norm(), tol * r_scale)
        << what << " step " << steps_checked << " m=" << rep.m;
    ++steps_checked;
  }
};

struct Family {
  const char* name;
  mesh::MeshData (*make)();
  SchurPreconditioner preconditioner;
  bool elastic = false;  ///< fem linear-elastic tangent (else the stand-in vector Laplacian)
  int seeds = 2;
  int steps = 30;
  double fixed_fraction = 0;  ///< nodes with z < zmin + fraction·(z range) are fixed (0: z = 0)
  /// Eq. 17 by GMRES or by the cached explicit Schur matrix (SchurSolver::kDirectCached).
  linalg::SchurSolver schur = linalg::SchurSolver::kGmres;
  int threads = 1;  ///< AugmentedOptions::solve_threads (step 3's backward pass)
};

void PrintTo(const Family& f, std::ostream* os) {
  *os << f.name;
}

/// 5×5×6 nodes.
mesh::MeshData small_beam() {
  return mesh::make_beam(6, 0.1);
}
/// 3×3×5 nodes.
mesh::MeshData small_brick() {
  return mesh::make_brick(2);
}
/// The liver of reference_data (3,721 vertices, 16,597 tetrahedra; MANIFEST.tsv), in metres.
mesh::MeshData liver() {
  io::ReadOptions o;
  o.scale = 0.001;
  return io::read_mesh(source_path("reference_data/meshes/liver_coarse.mesh"), o).mesh;
}

class AugmentedEquivalence : public ::testing::TestWithParam<Family> {};

// Yeung et al. 2016 eqs. 4–17: ≥ 200 random steps per default run across the parameter sets
// (9 families × 2 seeds × 30 steps — two with the cached Schur matrix, one with step 3 on two
// threads — plus 4 steps on the liver mesh), each compared with a fresh factorization.
TEST_P(AugmentedEquivalence, RandomCutsRemovalsConstraintsEq4to17) {
  const Family fam = GetParam();
  INCISE_SEEDED_RNG(rng, 5);
  const int seeds = fam.seeds;
  const int steps = scaled(fam.steps);
  int total = 0;
  for (int s = 0; s < seeds; ++s) {
    std::mt19937_64 r(rng());
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    AugmentedOptions opt;
    opt.gmres.tolerance = 1e-14;
    opt.gmres.restart = 300;
    opt.gmres.max_iterations = 3000;
    opt.preconditioner = fam.preconditioner;
    opt.schur_solver = fam.schur;
    opt.solve_threads = fam.threads;
    opt.cholmod.kind =
        (s % 2 == 0) ? linalg::CholmodKind::kSupernodal : linalg::CholmodKind::kSimplicialLdl;
    const mesh::MeshData mesh_data = fam.make();
    const double zmin = mesh_data.points.row(2).minCoeff();
    const double zrange = mesh_data.points.row(2).maxCoeff() - zmin;
    CutModel start = CutModel::from_mesh(
        mesh_data, fam.fixed_fraction > 0 ? zmin + fam.fixed_fraction * zrange : 1e-9);
    if (fam.elastic) start.use_linear_elastic(1e4, 0.3);
    Sequence seq(start, opt);
    // Initial load: pull on the far end.
    for (int v = 0; v < static_cast<int>(seq.model.node_dof.size()); ++v) {
      if (seq.model.node_dof[v] >= 0 &&
          seq.model.points(2, v) > seq.model.points.row(2).maxCoeff() - 1e-9)
        seq.f(seq.model.node_dof[v] + 1) = 1.0;
    }
    seq.check("initial");
    // Rejected proposals (singular candidates, no-op cuts) do not count as steps.
    for (int attempt = 0; seq.steps_checked <= steps && attempt < 20 * steps; ++attempt) {
      const double u = 0.5 * (unit(r) + 1.0);
      std::string what;
      CutModel cand = seq.model;
      std::map<int, double> cand_dir = seq.dirichlet;
      enum { kRemove, kAdd, kCut, kImpose, kRelease, kForce, kRefactor } op;
      if (u < 0.22)
        op = kRemove;
      else if (u < 0.34)
        op = kAdd;
      else if (u < 0.56)
        op = kCut;
      else if (u < 0.72)
        op = kImpose;
      else if (u < 0.82)
        op = kRelease;
      else if (u < 0.92)
        op = kForce;
      else
        op = kRefactor;
      int arg = -1;
      Eigen::Vector3d nrm = Eigen::Vector3d::Zero();
      std::vector<int> act, inact, movable;
      for (size_t e = 0; e < cand.tets.size(); ++e)
        (cand.active[e] ? act : inact).push_back(static_cast<int>(e));
      for (size_t v = 0; v < cand.node_dof.size(); ++v)
        if (cand.node_dof[v] >= 0) movable.push_back(static_cast<int>(v));
      auto pick = [&](const std::vector<int>& v) { return v[static_cast<size_t>(r() % v.size())]; };
      bool valid = true;
      switch (op) {
        case kRemove:
          what = "remove element";
          arg = pick(act);
          Sequence::remove(cand, nullptr, arg);
          break;
        case kAdd:
          what = "add element";
          if (inact.empty()) {
            valid = false;
            break;
          }
          arg = pick(inact);
          Sequence::add(cand, nullptr, arg);
          break;
        case kCut:
          what = "cut (duplicate node)";
          arg = pick(movable);
          nrm = Eigen::Vector3d(unit(r), unit(r), unit(r)).normalized();
          valid = Sequence::cut(cand, nullptr, arg, nrm);
          break;
        case kImpose:
          what = "impose Dirichlet";
          arg = pick(movable);
          for (int i = 0; i < 3; ++i) cand_dir[cand.node_dof[arg] + i] = 0.1 * unit(r);
          break;
        case kRelease:
          what = "release Dirichlet";
          if (cand_dir.empty()) {
            valid = false;
            break;
          }
          {
            auto it = cand_dir.begin();
            std::advance(it, static_cast<long>(r() % cand_dir.size()));
            arg = it->first;
            cand_dir.erase(it);
          }
          break;
        case kForce: what = "change forces"; break;
        case kRefactor: what = "refactorization"; break;
      }
      if (!valid) continue;
      if (op == kRemove || op == kCut || op == kRelease) {
        // Keep the modified system nonsingular (singular cases are tested separately).
        Eigen::VectorXd fc = Eigen::VectorXd::Zero(cand.num_dofs);
        if (!reference_solve(cand.assemble(), fc, cand_dir).ok) continue;
      }
      switch (op) {
        case kRemove:
          Sequence::remove(seq.model, &seq.aug, arg);
          ++seq.removals;
          break;
        case kAdd:
          Sequence::add(seq.model, &seq.aug, arg);
          ++seq.additions;
          break;
        case kCut:
          ASSERT_TRUE(Sequence::cut(seq.model, &seq.aug, arg, nrm));
          ++seq.cuts;
          break;
        case kImpose:
          for (int i = 0; i < 3; ++i)
            seq.aug.impose_dirichlet(cand.node_dof[arg] + i, cand_dir[cand.node_dof[arg] + i]);
          seq.dirichlet = cand_dir;
          ++seq.imposed;
          break;
        case kRelease:
          seq.aug.release_dirichlet(arg);
          seq.dirichlet = cand_dir;
          ++seq.released;
          break;
        case kForce:
          seq.f = Eigen::VectorXd::Zero(seq.model.num_dofs);
          for (int k = 0; k < 3; ++k) seq.f(static_cast<int>(r() % seq.model.num_dofs)) = unit(r);
          break;
        case kRefactor:
          if (!seq.aug.start_refactorization() || u > 0.96)
            (void)seq.aug.wait_for_refactorization();
          break;
      }
      seq.check(what.c_str());
      if (::testing::Test::HasFatalFailure()) return;
    }
    (void)seq.aug.wait_for_refactorization();
    seq.check("after final refactorization");
    total += seq.steps_checked;
    RecordProperty("cuts_" + std::to_string(s), seq.cuts);
    // The explicit H R⁻¹ J (capacitance form) equals the operator up to round-off, so as the
    // right preconditioner it leaves GMRES one iteration plus round-off corrections (measured
    // 1–3 here and on the 25,600-node beam cut). Its columns whose Ψ did not change are kept
    // from the solve before (issue 17; only the new labels' rows summed): exercised here, and
    // a stale kept column would show as extra iterations.
    if (fam.schur == linalg::SchurSolver::kDirectCached) {
      RecordProperty("max_direct_iterations_" + std::to_string(s), seq.max_gmres_iterations);
      EXPECT_LE(seq.max_gmres_iterations, 4) << "seed " << s;
      EXPECT_GT(seq.capacitance_columns_kept, 0) << "seed " << s;
    }
    // A long sequence must really exercise every kind of change (short ones: liver).
    if (steps >= 20) {
      EXPECT_GT(seq.cuts + seq.removals, 0);
      EXPECT_GT(seq.imposed, 0);
    }
  }
  EXPECT_GE(total, seeds * steps);
}

INSTANTIATE_TEST_SUITE_P(
    Families, AugmentedEquivalence,
    ::testing::Values(
        Family{"beam_diag", &small_beam, SchurPreconditioner::kDiagonal},
        Family{"brick_spai", &small_brick, SchurPreconditioner::kTridiagonalSpai},
        Family{"beam_none", &small_beam, SchurPreconditioner::kNone},
        Family{"brick_diag", &small_brick, SchurPreconditioner::kDiagonal},
        Family{"beam_elastic", &small_beam, SchurPreconditioner::kDiagonal, true},
        Family{"brick_elastic_spai", &small_brick, SchurPreconditioner::kTridiagonalSpai, true},
        Family{"liver_elastic", &liver, SchurPreconditioner::kDiagonal, true, 1, 4, 0.1},
        Family{"beam_elastic_direct", &small_beam, SchurPreconditioner::kNone, true, 2, 30, 0,
               linalg::SchurSolver::kDirectCached},
        Family{"brick_direct", &small_brick, SchurPreconditioner::kNone, false, 2, 30, 0,
               linalg::SchurSolver::kDirectCached},
        Family{"beam_elastic_threads2", &small_beam, SchurPreconditioner::kDiagonal, true, 2, 30, 0,
               linalg::SchurSolver::kGmres, 2}),
    [](const ::testing::TestParamInfo<Family>& p) { return std::string(p.param.name); });

// Eq. 1: replacing one column (and, by symmetry, its row) by an explicit example.
TEST(AugmentedEquivalence, SingleElementRemovalEq1) {
  CutModel m = CutModel::from_mesh(mesh::make_box(1, 1, 2, 1, 1, 2));
  AugmentedSystem aug;
  ASSERT_EQ(aug.initialize(m.assemble()), linalg::FactorStatus::kOk);
  Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(m.num_dofs, -1, 1);
  aug.add_element(m.dofs(0), m.element_matrix(0), -1.0);
  m.active[0] = 0;
  aug.set_force(f);
  Eigen::VectorXd a, r;
  const linalg::AugmentedReport rep = aug.solve(a, r);
  ASSERT_TRUE(rep.ok()) << rep.message;
  EXPECT_EQ(rep.m, aug.num_replaced());
  const ReferenceSolution ref = reference_solve(m.assemble(), f, {});
  ASSERT_TRUE(ref.ok);
  EXPECT_LE((a - ref.a).norm(), kRelTol * ref.a.norm());
  EXPECT_EQ(r.norm(), 0.0);
}

// SchurSolver::kDirectCached keeps the columns of the capacitance matrix Φ + GΨ whose Ψ did not
// change since the last solve and sums only the rows of labels new in 𝓛 (issue 17). After every
// step of a random sequence of element removals and additions, node duplications (§4.3.2, new
// DOFs) and Dirichlet impositions, the matrix the solve used equals H R⁻¹ J of eqs. 5, 6, 12,
// 17 formed from a dense inverse of K⁰ and the current columns of K, column by column. The
// capacitance form differs from it by round-off amplified by κ(R) (≈ 1e3–1e4 on this box):
// relative 1e-9 of each column's max-norm. A stale kept column differs by O(1).
TEST(AugmentedEquivalence, KeptCapacitanceColumnsEqualTheExplicitHRinvJ) {
  CutModel m = CutModel::from_mesh(mesh::make_box(3, 3, 4, 1, 1, 1.5));
  m.use_linear_elastic(1e4, 0.3);
  AugmentedOptions o;
  o.schur_solver = linalg::SchurSolver::kDirectCached;
  o.update_capacitance = true;
  AugmentedSystem aug(o);
  const linalg::SparseMatrix k0 = m.assemble();
  ASSERT_EQ(aug.initialize(k0), linalg::FactorStatus::kOk);
  const Eigen::MatrixXd r0inv = Eigen::MatrixXd(k0).inverse();
  const int n0 = static_cast<int>(k0.rows());
  INCISE_SEEDED_RNG(rng, 1721);
  std::uniform_int_distribution<int> pick_element(0, static_cast<int>(m.tets.size()) - 1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int kept = 0, checked = 0;
  for (int step = 0; step < 40; ++step) {
    const double p = u(rng);
    if (p < 0.3) {
      const int e = pick_element(rng);
      if (m.active[e]) {
        Sequence::remove(m, &aug, e);
      } else {
        Sequence::add(m, &aug, e);
      }
    } else if (p < 0.55) {
      const int node = static_cast<int>(u(rng) * static_cast<double>(m.points.cols() - 1));
      (void)Sequence::cut(m, &aug, node, Eigen::Vector3d(u(rng) - 0.5, u(rng) - 0.5, 1.0));
    } else if (p < 0.85) {  // mostly a DOF new to 𝓛: a new row in every kept column
      aug.impose_dirichlet(static_cast<int>(u(rng) * (m.num_dofs - 1)), 1e-3);
    }  // else: a solve with nothing changed
    Eigen::VectorXd f = Eigen::VectorXd::Zero(m.num_dofs), a, r;
    f(m.num_dofs - 1) = 1.0;
    aug.set_force(f);
    const linalg::AugmentedReport rep = aug.solve(a, r);
    if (!rep.ok()) continue;  // e.g. a removal that left a node without stiffness
    kept += rep.capacitance_columns_kept;
    const std::vector<int> l = aug.replaced_columns();
    const Eigen::MatrixXd& s = aug.last_capacitance_matrix();
    ASSERT_EQ(s.rows(), static_cast<Eigen::Index>(l.size()));
    const linalg::SparseMatrix k = m.assemble();
    for (std::size_t c = 0; c < l.size(); ++c) {
      Eigen::VectorXd j = Eigen::VectorXd::Zero(m.num_dofs);  // J_{*c} (eq. 5)
      if (aug.is_constrained(l[c])) {
        j(l[c]) = 1.0;
      } else {
        j = k.col(l[c]).toDense();
      }
      Eigen::VectorXd y =
          j;  // R⁻¹ J_{*c}: K⁰⁻¹ on the base DOFs, the identity on new ones (eq. 12)
      y.head(n0) = r0inv * j.head(n0);
      Eigen::VectorXd col(static_cast<Eigen::Index>(l.size()));
      for (std::size_t i = 0; i < l.size(); ++i) col(static_cast<Eigen::Index>(i)) = y(l[i]);
      const auto ci = static_cast<Eigen::Index>(c);
      EXPECT_LE((s.col(ci) - col).cwiseAbs().maxCoeff(), 1e-9 * col.cwiseAbs().maxCoeff())
          << "step " << step << ", column of DOF " << l[c];
    }
    ++checked;
  }
  EXPECT_GT(checked, 30);
  EXPECT_GT(kept, 0);  // the kept-column path ran
}

// 𝓛 pruning (AugmentedOptions::prune_unchanged_columns): element matrices rounded to multiples
// of 2⁻²⁰, so K⁰ and every update are exact sums and removing then re-adding an element gives K
// bitwise equal to R again: its columns must leave 𝓛 (m back to |𝓓|), and every solution must
// still equal a fresh factorization (eqs. 4–17 with the smaller 𝓛).
TEST(AugmentedEquivalence, UndoneChangesArePrunedFromL) {
  CutModel m = CutModel::from_mesh(mesh::make_box(2, 2, 3, 1, 1, 1.5));
  m.use_linear_elastic(1e4, 0.3);
  auto rounded = [&](int e) -> Eigen::MatrixXd {
    const Eigen::MatrixXd k = m.element_matrix(e);
    return ((k * 1048576.0).array().round() / 1048576.0).matrix();
  };
  auto assemble = [&]() {
    std::vector<Eigen::Triplet<double>> t;
    for (int e = 0; e < static_cast<int>(m.tets.size()); ++e) {
      if (!m.active[e]) continue;
      const std::vector<int> d = m.dofs(e);
      const Eigen::MatrixXd k = rounded(e);
      for (size_t a = 0; a < d.size(); ++a) {
        for (size_t b = 0; b < d.size(); ++b) {
          if (d[a] >= 0 && d[b] >= 0)
            t.emplace_back(d[a], d[b],
                           k(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)));
        }
      }
    }
    linalg::SparseMatrix k(m.num_dofs, m.num_dofs);
    k.setFromTriplets(t.begin(), t.end());
    return k;
  };
  AugmentedSystem aug;
  ASSERT_EQ(aug.initialize(assemble()), linalg::FactorStatus::kOk);
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(m.num_dofs, -1, 1);
  aug.set_force(f);
  std::map<int, double> dirichlet{{m.num_dofs - 1, 0.01}};
  aug.impose_dirichlet(m.num_dofs - 1, 0.01);
  int pruned = 0;
  auto check = [&](int expected_m, const char* what) {
    Eigen::VectorXd a, r;
    const linalg::AugmentedReport rep = aug.solve(a, r);
    pruned = rep.pruned_columns;
    ASSERT_TRUE(rep.ok()) << what << ": " << rep.message;
    if (expected_m >= 0) {
      EXPECT_EQ(rep.m, expected_m) << what;
    }
    const ReferenceSolution ref = reference_solve(assemble(), f, dirichlet);
    ASSERT_TRUE(ref.ok);
    EXPECT_LE((a - ref.a).norm(), kRelTol * ref.a.norm()) << what;
    EXPECT_LE((r - ref.r).norm(), kRelTol * std::max(ref.r.norm(), 1e-300)) << what;
  };
  check(1, "constraint only");
  const int e = static_cast<int>(m.tets.size()) / 2;
  aug.add_element(m.dofs(e), rounded(e), -1.0);
  m.active[e] = 0;
  check(-1, "element removed");
  EXPECT_GT(aug.num_replaced(), 1);
  aug.add_element(m.dofs(e), rounded(e), +1.0);
  m.active[e] = 1;
  check(1, "element added back: its columns pruned");
  EXPECT_GE(pruned, 9);  // the element's free DOFs (at least 3 of its 4 nodes are free)
  aug.release_dirichlet(m.num_dofs - 1);
  dirichlet.clear();
  check(0, "constraint released");
}

// Failure as status (issue 5): a DOF without stiffness (all its elements removed).
TEST(AugmentedFailure, DofWithoutStiffnessIsSingularStatus) {
  CutModel m = CutModel::from_mesh(mesh::make_box(1, 1, 2, 1, 1, 2));
  AugmentedSystem aug;
  ASSERT_EQ(aug.initialize(m.assemble()), linalg::FactorStatus::kOk);
  const int top = static_cast<int>(m.points.cols()) - 1;  // a top corner node
  for (size_t e = 0; e < m.tets.size(); ++e) {
    for (int a = 0; a < 4; ++a) {
      if (m.tets[e][a] == top && m.active[e]) {
        aug.add_element(m.dofs(static_cast<int>(e)), m.element_matrix(static_cast<int>(e)), -1);
        m.active[e] = 0;
      }
    }
  }
  Eigen::VectorXd f = Eigen::VectorXd::Ones(m.num_dofs);
  aug.set_force(f);
  Eigen::VectorXd a, r;
  const linalg::AugmentedReport rep = aug.solve(a, r);
  EXPECT_EQ(rep.status, AugmentedStatus::kSingularModifiedSystem) << rep.message;
  EXPECT_FALSE(rep.message.empty());
  EXPECT_TRUE(a.allFinite());
  // The fresh factorization of the same system reports not-positive-definite as well.
  linalg::CholmodFactor fac;
  EXPECT_EQ(fac.compute(m.assemble(), 1), linalg::FactorStatus::kNotPositiveDefinite);
}

// Failure as status: a cut through a whole layer frees the top part of a beam (rigid-body
// modes); with a net force on the freed part the system is inconsistent.
TEST(AugmentedFailure, CutFreeingComponentIsReported) {
  CutModel m = CutModel::from_mesh(mesh::make_box(1, 1, 3, 1, 1, 3));
  AugmentedSystem aug(AugmentedOptions{});
  ASSERT_EQ(aug.initialize(m.assemble()), linalg::FactorStatus::kOk);
  const int nodes = static_cast<int>(m.points.cols());
  for (int v = 0; v < nodes; ++v) {
    if (std::abs(m.points(2, v) - 2.0) < 1e-9) {
      ASSERT_TRUE(Sequence::cut(m, &aug, v, Eigen::Vector3d(0, 0, 1)));
    }
  }
  Eigen::VectorXd f = Eigen::VectorXd::Zero(m.num_dofs);
  for (int v = 0; v < nodes; ++v) {
    if (m.points(2, v) > 2.5) f(m.node_dof[v] + 2) = 1.0;  // net upward pull on the free part
  }
  aug.set_force(f);
  Eigen::VectorXd a, r;
  const linalg::AugmentedReport rep = aug.solve(a, r);
  EXPECT_NE(rep.status, AugmentedStatus::kOk)
      << "gmres " << linalg::to_string(rep.gmres.status) << " res " << rep.gmres.relative_residual
      << " hcond " << rep.gmres.hessenberg_condition << " it " << rep.gmres.iterations << " m "
      << rep.m << " |a| " << a.norm();
  EXPECT_FALSE(rep.message.empty());
  EXPECT_TRUE(a.allFinite());
  linalg::CholmodFactor fac;
  EXPECT_EQ(fac.compute(m.assemble(), 1), linalg::FactorStatus::kNotPositiveDefinite)
      << "rcond " << fac.rcond();
}

}  // namespace
}  // namespace incise::test
