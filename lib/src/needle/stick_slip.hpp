#pragma once
// Private to the needle module: the stick–slip rearrangements (§6.3.2), the release of nodes
// that slid off, and the solve/rearrange loop of §6.7 — shared by NeedleInsertion (2D) and
// NeedleInsertion3D; their contracts are in insertion.hpp (items 5 and 6).

#include <incise/core/timer.hpp>
#include <incise/core/types.hpp>
#include <incise/needle/insertion.hpp>
#include <incise/needle/needle.hpp>
#include <incise/needle/needle_problem.hpp>
#include <incise/solver/linear_cg.hpp>
#include <incise/solver/nonlinear_cg.hpp>

#include <algorithm>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

namespace incise::needle::detail {

// One rearrangement pass over all needle nodes (insertion.hpp item 5): `g` is the rotated
// gradient at the last solution (D components per vertex, the first along t), `fd` the dynamic
// thresholds. Returns the number of state changes.
template <int D, class Node>
int rearrange(std::vector<Node>& nodes, const std::vector<double>& fd, double static_factor,
              const VecX& g, const RearrangeMargins& margins) {
  int changes = 0;
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    Node& n = nodes[k];
    if (n.state == NodeState::kStick) {
      const double r = g[D * n.vertex];  // tangential reaction g̃_t
      if (std::abs(r) > static_factor * fd[k] + margins.force) {
        n.state = NodeState::kSlip;
        n.friction_sign = r > 0.0 ? 1 : -1;
        n.anchor = n.coords.s;
        ++changes;
      }
    } else if (n.friction_sign * (n.coords.s - n.anchor) < -margins.slide) {
      n.state = NodeState::kStick;
      n.friction_sign = 0;
      n.anchor = n.coords.s;
      ++changes;
    }
  }
  return changes;
}

// Releases the needle nodes with s < 0 or s > length (item 6), keeping `thresholds` aligned.
template <class Node>
int release(std::vector<Node>& nodes, std::vector<double>& thresholds, double length) {
  const std::size_t before = nodes.size();
  std::size_t kept = 0;
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    const Node& n = nodes[k];
    if (n.coords.s < 0.0 || n.coords.s > length) continue;
    nodes[kept] = n;
    thresholds[kept] = thresholds[k];
    ++kept;
  }
  nodes.resize(kept);
  thresholds.resize(kept);
  return static_cast<int>(before - kept);
}

// The solve → rearrange loop of one step (items 4–6): solve(rep) → bool, rearrange() → changes,
// fill(rep, converged) fills counts and the needle force, release() → released count. Adds
// the solves' wall time to rep.solve_seconds and the rest to rep.rearrange_seconds.
template <class Report, class Solve, class Rearrange, class Fill, class Release>
Report stick_slip_loop(Report rep, int max_rearrangements, Solve&& solve, Rearrange&& rearrange,
                       Fill&& fill, Release&& release) {
  for (;;) {
    Timer timer;
    const bool solved = solve(rep);
    rep.solve_seconds += timer.seconds();
    if (!solved) {
      fill(rep, false);
      return rep;
    }
    timer.restart();
    const int changes = rearrange();
    rep.rearrange_seconds += timer.seconds();
    if (changes == 0) break;
    if (rep.rearrangements >= max_rearrangements) {
      rep.status = StepStatus::kRearrangementCycle;
      rep.message = std::to_string(changes) + " needle nodes still change state after " +
                    std::to_string(rep.rearrangements) +
                    " rearrangements (max_rearrangements): the stick-slip iteration cycles";
      fill(rep, false);
      return rep;
    }
    ++rep.rearrangements;
  }
  Timer timer;
  fill(rep, true);
  rep.released = release();
  rep.rearrange_seconds += timer.seconds();
  rep.status = StepStatus::kOk;
  return rep;
}

// The end of every solve of (6.7), whichever solver produced the solution `ur` (rotated
// unknowns of `np`): u = R·ũ (original frame), the needle nodes' coordinates from the deformed
// positions (`points`: 3 × n reference positions) and the rotated gradient at the solution in
// `gradient`. False (status kSolverFailed) when the gradient cannot be evaluated.
template <int D, class Report>
bool conclude_solve(NeedleProblemT<D>& np, const typename NeedleSpace<D>::Pose& pose,
                    std::vector<typename NeedleSpace<D>::Node>& nodes,
                    const Eigen::Matrix3Xd& points, const VecX& ur, VecX& u, VecX& gradient,
                    Report& rep) {
  u = np.to_original(ur);
  for (auto& n : nodes)
    n.coords = pose.coordinates(points.col(n.vertex).template head<D>() +
                                u.template segment<D>(D * n.vertex));
  if (np.gradient(ur, gradient) != EvalStatus::kOk) {
    rep.status = StepStatus::kSolverFailed;
    rep.message = "gradient at the solution could not be evaluated";
    return false;
  }
  return true;
}

// One solve of (6.7) from the current state (item 4): builds the projected problem on `base`,
// runs the relaxation of `options` stopped by `stop` from u (original frame, updated on
// success), then refreshes the needle nodes' coordinates from the deformed positions
// (`points`: 3 × n reference positions) and stores the rotated gradient at the solution in
// `gradient`. Fills the solve counts of rep; false (status kSolverFailed) on failure.
// `precondition` (linear CG only), when set, is the operator preconditioner of the CG run
// (solver::LinearCgOptions::apply_preconditioner) instead of options.preconditioner;
// `precondition_failed` then says whether it failed during the run (a failed solve).
template <int D, class Report>
bool solve(typename NeedleSpace<D>::Base& base, const typename NeedleSpace<D>::Pose& pose,
           std::vector<typename NeedleSpace<D>::Node>& nodes, const std::vector<double>& friction,
           const InsertionOptions& options, const solver::StoppingRule& stop,
           const Eigen::Matrix3Xd& points, VecX& u, VecX& gradient, Report& rep,
           const std::function<void(const VecX&, VecX&)>& precondition = {},
           const std::function<bool()>& precondition_failed = {}) {
  NeedleProblemT<D> np(base, pose, nodes, friction);
  VecX ur = np.to_rotated(u);
  solver::SolverReport sr;
  if (options.relaxation == Relaxation::kLinearCg) {
    solver::LinearCgOptions o;
    o.stop = stop;
    o.budget.max_iterations = options.max_iterations;
    o.preconditioner = precondition ? solver::Preconditioner::kNone : options.preconditioner;
    o.apply_preconditioner = precondition;
    sr = solver::linear_cg(np, ur, o);
  } else {
    solver::NonlinearCgOptions o;
    o.stop = stop;
    o.budget.max_iterations = options.max_iterations;
    sr = solver::nonlinear_cg(np, ur, o);
  }
  ++rep.solves;
  rep.cg_iterations += sr.iterations;
  rep.flops += sr.flops;
  rep.max_cg_iterations = std::max(rep.max_cg_iterations, sr.iterations);
  rep.last_solver_status = sr.status;
  if (!sr.ok()) {
    rep.status = StepStatus::kSolverFailed;
    rep.message = "solve " + std::to_string(rep.solves) + ": " + sr.brief();
    return false;
  }
  if (precondition_failed && precondition_failed()) {
    rep.status = StepStatus::kSolverFailed;
    rep.message = "solve " + std::to_string(rep.solves) +
                  ": the factor preconditioner's triangular solve failed";
    return false;
  }
  return conclude_solve<D>(np, pose, nodes, points, ur, u, gradient, rep);
}

// Node counts and StepReport::needle_force (item 6 of the report): from the last solve's
// rotated gradient g̃ = Rᵀ(∇Π_el − f_friction) when no state changed since (`converged`),
// otherwise from a fresh gradient of `base` at u.
template <int D, class Report>
void fill_counts(typename NeedleSpace<D>::Base& base, const Eigen::Matrix<double, D, D>& frame,
                 const std::vector<typename NeedleSpace<D>::Node>& nodes,
                 const std::vector<double>& thresholds, const VecX& gradient, const VecX& u,
                 bool converged, Report& rep) {
  rep.sticking = rep.slipping = 0;
  for (const auto& n : nodes) (n.state == NodeState::kStick ? rep.sticking : rep.slipping)++;
  rep.needle_force.setZero();
  if (converged) {
    // No state changed since the last solve: its rotated gradient gives ∇Π_el at each needle
    // node without another sweep over the elements.
    for (std::size_t k = 0; k < nodes.size(); ++k) {
      const auto& nd = nodes[k];
      rep.needle_force +=
          frame * gradient.template segment<D>(D * nd.vertex) +
          (nd.state == NodeState::kSlip ? nd.friction_sign * thresholds[k] : 0.0) * frame.col(0);
    }
    return;
  }
  VecX g;
  if (base.gradient(u, g) == EvalStatus::kOk)
    for (const auto& nd : nodes) rep.needle_force += g.template segment<D>(D * nd.vertex);
}

}  // namespace incise::needle::detail
