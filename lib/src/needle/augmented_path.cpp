#include "augmented_path.hpp"

#include <incise/core/error.hpp>
#include <incise/fem/stiffness.hpp>
#include <incise/needle/needle_problem.hpp>

#include "stick_slip.hpp"

#include <algorithm>
#include <array>
#include <utility>

namespace incise::needle::detail {

namespace {

using CellKey = std::array<Index, 4>;

constexpr double kFrameTolerance = 1e-12;

// (sorted vertex set, column) of every cell, sorted by the set.
std::vector<std::pair<CellKey, Eigen::Index>> cell_keys(const mesh::CellMatrix& cells) {
  std::vector<std::pair<CellKey, Eigen::Index>> keys(static_cast<std::size_t>(cells.cols()));
  for (Eigen::Index e = 0; e < cells.cols(); ++e) {
    CellKey k{cells(0, e), cells(1, e), cells(2, e), cells(3, e)};
    std::sort(k.begin(), k.end());
    keys[static_cast<std::size_t>(e)] = {k, e};
  }
  std::sort(keys.begin(), keys.end());
  return keys;
}

}  // namespace

AugmentedNeedlePath::AugmentedNeedlePath(const material::Material& material)
    : material_(material), system_(linalg::interactive_options()) {}

bool AugmentedNeedlePath::matches(const Mat3& frame) const {
  // NeedlePose3D::moved along an unchanged direction renormalizes: the frame may move by
  // rounding. Within kFrameTolerance the factored frame serves (a constraint direction off by
  // 1e-12 rad moves a slipping node's path by 1e-12 of its slip).
  return ready_ && (frame - frame_).cwiseAbs().maxCoeff() <= kFrameTolerance;
}

bool AugmentedNeedlePath::reset(const fem::ElasticProblem& problem, const Mat3& frame,
                                std::string& message) {
  ready_ = false;
  constrained_.clear();
  mesh::MeshData body;
  body.points = problem.points();
  body.cells = problem.cells();
  linalg::SparseMatrix k = fem::assemble_stiffness(body, material_);
  const Index nv = problem.num_nodes();
  fixed_.assign(static_cast<std::size_t>(nv), 0);
  for (Index v = 0; v < nv; ++v) fixed_[static_cast<std::size_t>(v)] = problem.is_fixed(3 * v);
  // Fixed DOFs decoupled with a unit diagonal (the pattern is kept; K̃ stays symmetric).
  for (Eigen::Index j = 0; j < k.outerSize(); ++j)
    for (linalg::SparseMatrix::InnerIterator it(k, j); it; ++it) {
      const bool fr = fixed_[static_cast<std::size_t>(it.row() / 3)] != 0;
      const bool fc = fixed_[static_cast<std::size_t>(it.col() / 3)] != 0;
      if (fr || fc) it.valueRef() = it.row() == it.col() ? 1.0 : 0.0;
    }
  // K̃ = PᵀKP, P = blockdiag(Q): P is orthogonal, so a unit-diagonal fixed block stays one.
  std::vector<Eigen::Triplet<double>> pt;
  pt.reserve(static_cast<std::size_t>(9 * nv));
  for (Index v = 0; v < nv; ++v)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) pt.emplace_back(3 * v + r, 3 * v + c, frame(r, c));
  linalg::SparseMatrix p(3 * nv, 3 * nv);
  p.setFromTriplets(pt.begin(), pt.end());
  linalg::SparseMatrix kt = linalg::SparseMatrix(p.transpose()) * k * p;
  // Exact symmetry of the stored values (the two triangles are computed by different sums).
  kt = 0.5 * (kt + linalg::SparseMatrix(kt.transpose()));
  frame_ = frame;
  cells_ = problem.cells();
  const linalg::FactorStatus fs = system_.initialize(kt);
  ++factorizations_;
  if (fs != linalg::FactorStatus::kOk) {
    message = std::string("the factorization of the needle-frame stiffness failed (") +
              linalg::to_string(fs) + ": " + system_.factorization_message() + ")";
    return false;
  }
  ready_ = true;
  return true;
}

std::vector<int> AugmentedNeedlePath::element_dofs(const mesh::CellMatrix& cells,
                                                   Eigen::Index e) const {
  std::vector<int> d(12, -1);
  for (int a = 0; a < 4; ++a) {
    const Index v = cells(a, e);
    if (fixed_[static_cast<std::size_t>(v)]) continue;
    for (int i = 0; i < 3; ++i)
      d[static_cast<std::size_t>(3 * a + i)] = static_cast<int>(3 * v + i);
  }
  return d;
}

void AugmentedNeedlePath::add_cell(const Eigen::Matrix3Xd& points, const mesh::CellMatrix& cells,
                                   Eigen::Index e, double scale) {
  fem::Mat34T<double> x;
  for (int a = 0; a < 4; ++a) x.col(a) = points.col(cells(a, e));
  fem::Mat12T<double> ke;
  // A refinement of a positively oriented mesh keeps every volume positive; were one not, ke
  // is zero, as fem::assemble_stiffness would refuse the mesh.
  (void)fem::element_stiffness(material_, x, fem::Mat34T<double>::Zero(), ke);
  fem::Mat12T<double> b = fem::Mat12T<double>::Zero();
  for (int a = 0; a < 4; ++a) b.block<3, 3>(3 * a, 3 * a) = frame_;
  const Eigen::MatrixXd kr = b.transpose() * ke * b;
  system_.add_element(element_dofs(cells, e), 0.5 * (kr + kr.transpose()), scale);
}

void AugmentedNeedlePath::follow(const fem::ElasticProblem& problem) {
  INCISE_ASSERT(ready_, "AugmentedNeedlePath::follow before reset");
  const Index old_nv = static_cast<Index>(fixed_.size());
  const Index nv = problem.num_nodes();
  INCISE_ASSERT(nv >= old_nv, "a refinement only adds vertices");
  for (Index v = old_nv; v < nv; ++v) {
    const int first = system_.add_dofs(3);
    INCISE_ASSERT(first == 3 * v, "DOF 3·v + c is vertex v's");
    const bool fixed = problem.is_fixed(3 * v);
    fixed_.push_back(fixed ? 1 : 0);
    if (fixed) system_.add_element({first, first + 1, first + 2}, Eigen::Matrix3d::Identity());
  }
  const auto before = cell_keys(cells_);
  const auto after = cell_keys(problem.cells());
  // Only cells differ between a mesh and its refinement: merge the two sorted lists.
  std::size_t i = 0, j = 0;
  while (i < before.size() || j < after.size()) {
    if (j == after.size() || (i < before.size() && before[i].first < after[j].first)) {
      add_cell(problem.points(), cells_, before[i++].second, -1.0);  // a bisected cell
    } else if (i == before.size() || after[j].first < before[i].first) {
      add_cell(problem.points(), problem.cells(), after[j++].second, 1.0);  // a new child
    } else {
      ++i;
      ++j;
    }
  }
  cells_ = problem.cells();
}

int AugmentedNeedlePath::changed_columns() const {
  return system_.num_replaced() - static_cast<int>(constrained_.size());
}

bool AugmentedNeedlePath::refactor() {
  const bool ok = system_.refactor_now();
  if (ok) ++factorizations_;
  return ok;
}

bool AugmentedNeedlePath::solve(fem::ElasticProblem& problem, const NeedlePose3D& pose,
                                std::vector<NeedleNode3D>& nodes,
                                const std::vector<double>& friction, const Eigen::Matrix3Xd& points,
                                VecX& u, VecX& gradient, StepReport3D& rep) {
  INCISE_ASSERT(matches(pose.frame()), "AugmentedNeedlePath::solve in another frame");
  NeedleProblem3D np(problem, pose, nodes, friction);
  // The constraints of this solve: components (t, n1, n2) = 0, 1, 2 of ã = Qᵀu at the node.
  std::vector<std::pair<int, double>> want;
  for (const NeedleNode3D& n : nodes) {
    const Vec3 a = frame_.transpose() * u.segment<3>(3 * n.vertex);
    for (int c = n.state == NodeState::kStick ? 0 : 1; c < 3; ++c)
      want.emplace_back(static_cast<int>(3 * n.vertex + c), a(c));
  }
  std::set<int> now;
  for (const auto& w : want) now.insert(w.first);
  for (int d : constrained_)
    if (now.count(d) == 0) system_.release_dirichlet(d);
  for (const auto& w : want) system_.impose_dirichlet(w.first, w.second);
  constrained_ = std::move(now);
  // Loads f_ext + friction, rotated; zero at the fixed vertices.
  const VecX f = problem.external_force() + np.friction_force();
  VecX ft(f.size());
  for (Eigen::Index v = 0; v < f.size() / 3; ++v)
    ft.segment<3>(3 * v) = fixed_[static_cast<std::size_t>(v)]
                               ? Vec3::Zero()
                               : Vec3(frame_.transpose() * f.segment<3>(3 * v));
  system_.set_force(ft);
  VecX a, reaction;
  const linalg::AugmentedReport ar = system_.solve(a, reaction);
  ++rep.solves;
  rep.replaced_columns = ar.m;
  if (!ar.ok()) {
    rep.status = StepStatus::kSolverFailed;
    rep.message = "augmented solve " + std::to_string(rep.solves) + ": " + ar.brief();
    return false;
  }
  VecX uo(a.size());
  for (Eigen::Index v = 0; v < a.size() / 3; ++v)
    uo.segment<3>(3 * v) = frame_ * a.segment<3>(3 * v);
  return conclude_solve<3>(np, pose, nodes, points, np.to_rotated(uo), u, gradient, rep);
}

}  // namespace incise::needle::detail
