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

}  // namespace incise::interactive
