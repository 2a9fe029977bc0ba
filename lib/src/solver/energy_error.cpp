#include <incise/solver/energy_error.hpp>

#include <algorithm>
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

const char* to_string(InversionStatus s) {
  return s == InversionStatus::kInverted ? "inverted" : "none_inverted";
}

InversionCheck check_inversion(const Eigen::Matrix3Xd& points,
                               const Eigen::Matrix<Index, Eigen::Dynamic, Eigen::Dynamic>& cells,
                               const VecX& u) {
  INCISE_CHECK_PARAM(cells.rows() == 4 || cells.cols() == 0,
                     "check_inversion: cells must be 4 x m (tetrahedra)");
  INCISE_CHECK_PARAM(u.size() == 3 * points.cols(),
                     "check_inversion: u must have 3 entries per node");
  InversionCheck out;
  for (Eigen::Index e = 0; e < cells.cols(); ++e) {
    Vec3 x[4], X[4];
    for (int a = 0; a < 4; ++a) {
      const Index n = cells(a, e);
      INCISE_CHECK_PARAM(n >= 0 && n < points.cols(), "check_inversion: vertex index out of range");
      X[a] = points.col(n);
      x[a] = X[a] + u.segment<3>(3 * Eigen::Index(n));
    }
    const double v0 = (X[1] - X[0]).cross(X[2] - X[0]).dot(X[3] - X[0]);
    const double v = (x[1] - x[0]).cross(x[2] - x[0]).dot(x[3] - x[0]);
    out.min_volume_ratio = std::min(out.min_volume_ratio, v / v0);
    if (!(v > 0.0)) {
      ++out.inverted_elements;
      out.elements.push_back(Index(e));
    }
  }
  if (out.inverted_elements > 0) out.status = InversionStatus::kInverted;
  return out;
}

}  // namespace incise::solver
