#include <incise/core/error.hpp>
#include <incise/linalg/cholmod_factor.hpp>
#include <incise/needle/needle_problem.hpp>

#include <string>
#include <vector>

namespace incise::needle {

template <int D>
NeedleProblemT<D>::NeedleProblemT(Base& base, const Pose& pose, const std::vector<Node>& nodes,
                                  const std::vector<double>& friction)
    : base_(base), frame_(pose.frame()) {
  INCISE_CHECK(friction.size() == nodes.size(), "NeedleProblem: friction has the wrong size");
  const auto n = static_cast<std::size_t>(base.size());
  fixed_.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) fixed_[i] = base.is_fixed(static_cast<Eigen::Index>(i));
  f_fric_ = VecX::Zero(base.size());
  std::vector<char> seen(static_cast<std::size_t>(base.num_nodes()), 0);
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    const Node& nd = nodes[k];
    const Index v = nd.vertex;
    INCISE_CHECK(v >= 0 && v < base.num_nodes(),
                 "NeedleProblem: needle vertex " + std::to_string(v) + " is out of range");
    INCISE_CHECK(!seen[static_cast<std::size_t>(v)],
                 "NeedleProblem: needle vertex " + std::to_string(v) + " is listed twice");
    seen[static_cast<std::size_t>(v)] = 1;
    for (int c = 0; c < D; ++c)
      INCISE_CHECK(!base.is_fixed(D * v + c),
                   "NeedleProblem: needle vertex " + std::to_string(v) + " is fixed in the body");
    needle_vertices_.push_back(v);
    for (int c = 1; c < D; ++c) fixed_[static_cast<std::size_t>(D * v + c)] = 1;
    if (nd.state == NodeState::kStick) {
      fixed_[static_cast<std::size_t>(D * v)] = 1;
    } else {
      INCISE_CHECK(
          nd.friction_sign == 1 || nd.friction_sign == -1,
          "NeedleProblem: slipping vertex " + std::to_string(v) + " needs friction_sign +1 or -1");
      f_fric_.template segment<D>(D * v) = (nd.friction_sign * friction[k]) * frame_.col(0);
    }
  }
  for (std::size_t i = 0; i < n; ++i)
    if (fixed_[i]) fixed_list_.push_back(static_cast<Eigen::Index>(i));
}

template <int D>
void NeedleProblemT<D>::rotate(VecX& v, bool transpose) const {
  // Rᵀ maps x to its frame components (x·t, x·n…); R maps them back.
  for (const Index i : needle_vertices_) {
    const VecD x = v.template segment<D>(D * i);
    if (transpose)
      v.template segment<D>(D * i) = frame_.transpose() * x;
    else
      v.template segment<D>(D * i) = frame_ * x;
  }
  own_flops_ += (2 * D * D - D) * needle_vertices_.size();
}

template <int D>
VecX NeedleProblemT<D>::to_rotated(const VecX& u) const {
  INCISE_CHECK(u.size() == size(), "NeedleProblem::to_rotated: wrong size");
  VecX r = u;
  rotate(r, true);
  return r;
}

template <int D>
VecX NeedleProblemT<D>::to_original(const VecX& rotated) const {
  INCISE_CHECK(rotated.size() == size(), "NeedleProblem::to_original: wrong size");
  VecX u = rotated;
  rotate(u, false);
  return u;
}

template <int D>
void NeedleProblemT<D>::project_original(VecX& v) const {
  rotate(v, true);
  project(v);
  rotate(v, false);
}

template <int D>
Eigen::SparseMatrix<double> NeedleProblemT<D>::rotation() const {
  std::vector<Eigen::Triplet<double>> t;
  std::vector<char> needle(static_cast<std::size_t>(base_.num_nodes()), 0);
  for (const Index i : needle_vertices_) {
    needle[static_cast<std::size_t>(i)] = 1;
    // Column D·i + c: rotated component c of node i (along frame column c).
    for (int c = 0; c < D; ++c)
      for (int r = 0; r < D; ++r) t.emplace_back(D * i + r, D * i + c, frame_(r, c));
  }
  for (Index i = 0; i < base_.num_nodes(); ++i)
    if (!needle[static_cast<std::size_t>(i)])
      for (int c = 0; c < D; ++c) t.emplace_back(D * i + c, D * i + c, 1.0);
  Eigen::SparseMatrix<double> r(size(), size());
  r.setFromTriplets(t.begin(), t.end());
  return r;
}

template <int D>
EvalStatus NeedleProblemT<D>::energy(const VecX& u, double& energy) {
  const VecX x = to_original(u);
  const EvalStatus s = base_.energy(x, energy);
  if (s == EvalStatus::kOk) energy -= f_fric_.dot(x);
  own_flops_ += 2 * static_cast<std::uint64_t>(size());
  return s;
}

template <int D>
EvalStatus NeedleProblemT<D>::gradient(const VecX& u, VecX& g, double* energy) {
  // The 2D base problem keeps its last gradient: the interaction loop's repeated requests at
  // the solver's final iterate, and the next solve's start after the needle moved a few nodes,
  // are answered without a sweep (PlaneStressProblem::gradient).
  if (has_last_ && (last_has_energy_ || !energy) && u.size() == last_u_.size() && u == last_u_) {
    g = last_g_;
    if (energy) *energy = last_energy_;
    return EvalStatus::kOk;
  }
  has_last_ = false;
  x_ = u;
  rotate(x_, false);
  const EvalStatus s = base_.gradient(x_, g, energy);
  if (s != EvalStatus::kOk) return s;
  g -= f_fric_;
  if (energy) *energy -= f_fric_.dot(x_);
  own_flops_ += 3 * static_cast<std::uint64_t>(size());
  rotate(g, true);
  last_u_ = u;
  last_g_ = g;
  last_has_energy_ = energy != nullptr;
  last_energy_ = energy ? *energy : 0.0;
  has_last_ = true;
  return s;
}

template <int D>
EvalStatus NeedleProblemT<D>::hessian_product(const VecX& u, const VecX& d, VecX& out) {
  dx_ = d;
  rotate(dx_, false);
  // A constant tangent does not depend on the point: u need not be rotated back then.
  bool constant = false;
  if constexpr (D == 2)
    constant = base_.has_constant_tangent();
  else
    constant = base_.energy_is_quadratic();  // linear geometry: one K (elastic_problem.hpp)
  if (!constant) {
    x_ = u;
    rotate(x_, false);
  }
  const EvalStatus s = base_.hessian_product(constant ? u : x_, dx_, out);
  if (s == EvalStatus::kOk) rotate(out, true);
  return s;
}

template <int D>
bool NeedleProblemT<D>::hessian_diagonal(const VecX& u, VecX& diag) {
  x_ = u;
  rotate(x_, false);
  if (!base_.hessian_diagonal(x_, diag)) return false;
  for (const Index i : needle_vertices_) {
    const VecD k = diag.template segment<D>(D * i);
    diag.template segment<D>(D * i) = frame_.cwiseAbs2().transpose() * k;
  }
  for (Eigen::Index i = 0; i < diag.size(); ++i)
    if (fixed_[static_cast<std::size_t>(i)]) diag[i] = 1.0;
  return true;
}

template <int D>
void NeedleProblemT<D>::project(VecX& v) const {
  for (const Eigen::Index i : fixed_list_) v[i] = 0.0;
}

template <int D>
double NeedleProblemT<D>::external_force_norm() const {
  VecX f = base_.external_force() + f_fric_;
  rotate(f, true);
  project(f);
  return f.norm();
}

template <int D>
std::uint64_t NeedleProblemT<D>::flops() const {
  return base_.flops() + own_flops_;
}

const char* to_string(DirectStatus s) {
  switch (s) {
    case DirectStatus::kOk: return "ok";
    case DirectStatus::kEvalFailed: return "eval-failed";
    case DirectStatus::kFactorFailed: return "factor-failed";
  }
  return "?";
}

template <int D>
DirectOutcome direct_solve(NeedleProblemT<D>& problem, VecX& rotated) {
  DirectOutcome out;
  auto& base = problem.base();
  const VecX x = problem.to_original(rotated);
  Eigen::SparseMatrix<double> k;
  EvalStatus s = base.tangent(x, k);
  VecX g;
  if (s == EvalStatus::kOk) s = problem.gradient(rotated, g);
  if (s != EvalStatus::kOk || !g.allFinite()) {
    out.status = DirectStatus::kEvalFailed;
    out.message = std::string("tangent or gradient: ") + incise::to_string(s);
    return out;
  }
  const Eigen::SparseMatrix<double> r = problem.rotation();
  const Eigen::SparseMatrix<double> kr = Eigen::SparseMatrix<double>(r.transpose()) * k * r;
  const Eigen::Index n = problem.size();
  std::vector<int> free_index(static_cast<std::size_t>(n), -1);
  std::vector<Eigen::Index> free;
  for (Eigen::Index i = 0; i < n; ++i)
    if (!problem.is_fixed(i)) {
      free_index[static_cast<std::size_t>(i)] = static_cast<int>(free.size());
      free.push_back(i);
    }
  const auto m = static_cast<Eigen::Index>(free.size());
  if (m == 0) {
    out.status = DirectStatus::kOk;
    return out;
  }
  std::vector<Eigen::Triplet<double>> trip;
  for (int c = 0; c < kr.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(kr, c); it; ++it) {
      const int fr = free_index[static_cast<std::size_t>(it.row())];
      const int fc = free_index[static_cast<std::size_t>(it.col())];
      if (fr >= 0 && fc >= 0 && fr >= fc) trip.emplace_back(fr, fc, it.value());
    }
  linalg::SparseMatrix kff(static_cast<int>(m), static_cast<int>(m));
  kff.setFromTriplets(trip.begin(), trip.end());
  VecX rhs(m);
  for (Eigen::Index j = 0; j < m; ++j) rhs[j] = -g[free[static_cast<std::size_t>(j)]];
  linalg::CholmodFactor factor;
  VecX delta;
  if (factor.compute(kff, 1) != linalg::FactorStatus::kOk ||
      factor.solve(rhs, delta) != linalg::FactorStatus::kOk) {
    out.status = DirectStatus::kFactorFailed;
    out.message =
        std::string("CHOLMOD: ") + linalg::to_string(factor.info()) + " " + factor.message();
    return out;
  }
  for (Eigen::Index j = 0; j < m; ++j) rotated[free[static_cast<std::size_t>(j)]] += delta[j];
  out.status = DirectStatus::kOk;
  return out;
}

template class NeedleProblemT<2>;
template class NeedleProblemT<3>;
template DirectOutcome direct_solve<2>(NeedleProblemT<2>&, VecX&);
template DirectOutcome direct_solve<3>(NeedleProblemT<3>&, VecX&);

}  // namespace incise::needle
