#include <incise/core/error.hpp>
#include <incise/interactive/refactorization_policy.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace incise::interactive {

void RefactorizationPolicy::observe(double seconds, bool swapped) {
  INCISE_CHECK_PARAM(std::isfinite(seconds) && seconds >= 0,
                     "RefactorizationPolicy::observe: the update cost must be finite and >= 0");
  if (swapped) reset();
  floor_ = std::min(floor_, seconds);
  excess_ += seconds - floor_;
}

bool RefactorizationPolicy::should_start(double factorization_seconds) const {
  if (mode_ == RefactorizationMode::kContinuous) return true;
  return factorization_seconds > 0 && excess_ >= factorization_seconds;
}

void RefactorizationPolicy::reset() {
  floor_ = std::numeric_limits<double>::infinity();
  excess_ = 0;
}

void SynchronousRefactorRule::observe(int m, int k, double cpu_total, double cpu_capacitance,
                                      bool fresh, double cpu_columns) {
  if (m <= 0 || !(cpu_total >= 0) || !(cpu_capacitance >= 0) || !(cpu_columns >= 0)) return;
  const double md = static_cast<double>(m);
  if (fresh && m >= kMinRateM && cpu_capacitance > 0)
    lu_rate_ = (2.0 / 3.0) * md * md * md / cpu_capacitance;
  if (k >= kMinColumns) column_ = cpu_columns / static_cast<double>(k);
  rest_ = std::max(0.0, cpu_total - cpu_capacitance - cpu_columns) / md;
}

double SynchronousRefactorRule::predict(int m, int k) const {
  if (!(lu_rate_ > 0) || !std::isfinite(column_) || !std::isfinite(rest_))
    return std::numeric_limits<double>::quiet_NaN();
  const double md = static_cast<double>(std::max(m, 0));
  return (2.0 / 3.0) * md * md * md / lu_rate_ + column_ * static_cast<double>(std::max(k, 0)) +
         rest_ * md;
}

bool SynchronousRefactorRule::should_refactor(int m, int k, double refactor_cpu) const {
  return worth_refactoring(predict(m, k), refactor_cpu);
}

}  // namespace incise::interactive
