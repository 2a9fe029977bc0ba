#include <incise/solver/energy_error.hpp>

#include <cmath>
#include <limits>
#include <utility>

namespace incise::solver {

EnergyErrorTrace::EnergyErrorTrace(Problem& problem, VecX reference)
    : problem_(problem), reference_(std::move(reference)) {
  INCISE_CHECK(reference_.size() == problem_.size(), "EnergyErrorTrace: reference size mismatch");
}

double EnergyErrorTrace::energy_error(const VecX& u) {
  INCISE_CHECK(u.size() == reference_.size(), "EnergyErrorTrace: u size mismatch");
  e_ = u - reference_;
  problem_.project(e_);
  if (problem_.hessian_product(reference_, e_, ke_) != EvalStatus::kOk || !ke_.allFinite())
    return std::numeric_limits<double>::infinity();
  const double v = e_.dot(ke_);
  return std::isfinite(v) ? v : std::numeric_limits<double>::infinity();
}

void EnergyErrorTrace::record_start(const VecX& u0, double residual_norm) {
  samples_.push_back(Sample{0, 0.0, 0, energy_error(u0), residual_norm});
}

IterationObserver EnergyErrorTrace::observer() {
  return [this](const IterationInfo& info) {
    samples_.push_back(Sample{info.iteration, info.seconds, info.flops, energy_error(*info.u),
                              info.residual_norm});
  };
}

const EnergyErrorTrace::Sample* EnergyErrorTrace::first_below(double level) const {
  for (const Sample& s : samples_)
    if (s.energy_error <= level) return &s;
  return nullptr;
}

}  // namespace incise::solver
