#include <incise/core/error.hpp>
#include <incise/needle/friction.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

namespace incise::needle {

void FrictionProfile::validate() const {
  INCISE_CHECK_PARAM(
      std::isfinite(shaft_density) && shaft_density >= 0.0,
      "friction shaft density must be finite and >= 0, got " + std::to_string(shaft_density));
  INCISE_CHECK_PARAM(
      std::isfinite(tip_density) && tip_density >= 0.0,
      "friction tip density must be finite and >= 0, got " + std::to_string(tip_density));
  INCISE_CHECK_PARAM(
      std::isfinite(bulge_length) && bulge_length > 0.0,
      "friction bulge length must be finite and > 0, got " + std::to_string(bulge_length));
  INCISE_CHECK_PARAM(
      std::isfinite(static_factor) && static_factor >= 1.0,
      "static friction factor must be finite and >= 1, got " + std::to_string(static_factor));
}

double FrictionProfile::density(double s) const {
  if (s < 0.0) return 0.0;
  return shaft_density + (tip_density - shaft_density) * std::max(0.0, 1.0 - s / bulge_length);
}

double FrictionProfile::integral(double a, double b) const {
  INCISE_CHECK(a <= b, "FrictionProfile::integral: a > b");
  a = std::max(a, 0.0);
  b = std::max(b, 0.0);
  // G(x) = ∫_0^x max(0, 1 − s/ℓ) ds.
  const auto g = [&](double x) {
    return x >= bulge_length ? 0.5 * bulge_length : x - x * x / (2.0 * bulge_length);
  };
  return shaft_density * (b - a) + (tip_density - shaft_density) * (g(b) - g(a));
}

std::vector<double> FrictionProfile::dynamic_thresholds(const std::vector<double>& s) const {
  const std::size_t n = s.size();
  std::vector<double> out(n, 0.0);
  if (n == 0) return out;
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return s[a] < s[b]; });
  double lo = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    const double hi =
        k + 1 < n ? 0.5 * (s[order[k]] + s[order[k + 1]]) : std::max(s[order[k]], 0.0);
    const double a = std::max(lo, 0.0), b = std::max(hi, a);
    out[order[k]] = integral(a, b);
    lo = b;
  }
  return out;
}

std::vector<double> FrictionProfile::surface_thresholds(const std::vector<double>& s,
                                                        const std::vector<double>& area,
                                                        double radius) const {
  INCISE_CHECK(s.size() == area.size(), "surface_thresholds: s and area differ in size");
  INCISE_CHECK_PARAM(std::isfinite(radius) && radius > 0.0,
                     "needle radius must be finite and > 0, got " + std::to_string(radius));
  const double per_area = 1.0 / (2.0 * M_PI * radius);
  std::vector<double> out(s.size());
  for (std::size_t k = 0; k < s.size(); ++k) out[k] = density(s[k]) * area[k] * per_area;
  return out;
}

}  // namespace incise::needle
