#pragma once
/// \file derivative_check.hpp
/// Directional-derivative checks shared by the material and fem property tests (DESIGN §3:
/// "central differences with a step sweep ... a Taylor-remainder test whose order must come out
/// ≈ 2"). A scalar function φ(h) = ψ(x + h·d) and its claimed derivative φ'(0) are checked by
/// - a central-difference sweep h = s·10⁻², …, s·10⁻⁸: best relative error over the sweep;
/// - the Taylor remainder r(h) = |φ(h) − φ(0) − h φ'(0)| for h = s·2⁻ᵏ: observed order
///   log2(r(h)/r(h/2)), the median of the three smallest-step pairs still well above round-off
///   (a wrong derivative gives order 1 there). When r stays at round-off for every h (φ linear in
///   h) the order is reported as +∞ ("exact").
/// Matrix- and vector-valued maps are reduced to scalars by contracting with a fixed random
/// weight, which detects a wrong derivative with probability one.

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace incise::test {

/// Result of check_directional_derivative.
struct DerivativeCheck {
  double best_relative_error = std::numeric_limits<double>::infinity();
  double best_step = 0.0;
  double taylor_order = 0.0;  ///< +∞ when φ is linear to round-off
  std::string report;         ///< the sweep, for failure messages
};

/// Checks φ'(0) = `derivative` for φ = `phi`. `step_scale` s sets the step sizes (the distance
/// over which φ is smooth); `unit` is the scale below which errors are measured absolutely
/// (the magnitude of a typical derivative, so φ'(0) = 0 is handled).
/// `value_scale` is the magnitude of the terms that make up φ (when φ is a contraction with
/// cancellation, |φ| understates its round-off).
inline DerivativeCheck check_directional_derivative(const std::function<double(double)>& phi,
                                                    double derivative, double step_scale,
                                                    double unit, double value_scale = 0.0) {
  DerivativeCheck out;
  const double denom = std::max(std::abs(derivative), unit);
  std::string rep = "central differences (h, rel.err):";
  for (int k = 2; k <= 8; ++k) {
    const double h = step_scale * std::pow(10.0, -k);
    const double fd = (phi(h) - phi(-h)) / (2.0 * h);
    const double err = std::abs(fd - derivative) / denom;
    rep += " (" + std::to_string(h) + ", " + std::to_string(err) + ")";
    if (err < out.best_relative_error) {
      out.best_relative_error = err;
      out.best_step = h;
    }
  }
  const double phi0 = phi(0.0);
  const double eps = std::numeric_limits<double>::epsilon();
  std::vector<double> r;
  std::vector<double> floor;
  for (int k = 0; k <= 16; ++k) {
    const double h = step_scale * std::ldexp(1.0, -k);
    r.push_back(std::abs(phi(h) - phi0 - h * derivative));
    // Round-off floor of the remainder: a few hundred ulps of the values involved.
    floor.push_back(256.0 * eps *
                    (std::abs(phi0) + value_scale + std::abs(h * derivative) + h * unit));
  }
  // Orders log2(r(h)/r(h/2)) over the pairs well above round-off (1000× the floor); curvature
  // can fake order 2 at the largest steps, a wrong derivative shows order 1 at the smallest.
  rep += "; Taylor orders:";
  std::vector<double> orders;
  for (std::size_t k = 0; k + 1 < r.size(); ++k) {
    if (r[k + 1] <= 1000.0 * floor[k + 1] || r[k] <= 1000.0 * floor[k]) continue;
    const double o = std::log2(r[k] / r[k + 1]);
    rep += " " + std::to_string(o);
    orders.push_back(o);
  }
  if (orders.empty()) {
    out.taylor_order = std::numeric_limits<double>::infinity();
  } else {
    // Median of the (up to) three smallest-step pairs: past the pre-asymptotic large steps,
    // robust to one pair disturbed by round-off.
    std::vector<double> tail(
        orders.end() - std::min<std::ptrdiff_t>(3, static_cast<std::ptrdiff_t>(orders.size())),
        orders.end());
    std::sort(tail.begin(), tail.end());
    out.taylor_order = tail[tail.size() / 2];
  }
  out.report = rep;
  return out;
}

/// Taylor order for a vector-valued map: r(h) = ‖f(h) − f(0) − h·f'(0)‖ for h = s·2⁻ᵏ, the
/// median of the three smallest-step orders with r above 1000× the round-off floor
/// 256·ε·`value_scale`; +∞ when r never rises above it (f linear).
template <class Vec>
double vector_taylor_order(const std::function<Vec(double)>& f, const Vec& derivative,
                           double step_scale, double value_scale, std::string* report = nullptr) {
  const Vec f0 = f(0.0);
  const double floor = 1000.0 * 256.0 * std::numeric_limits<double>::epsilon() * value_scale;
  std::vector<double> r;
  for (int k = 0; k <= 16; ++k) {
    const double h = step_scale * std::ldexp(1.0, -k);
    r.push_back((f(h) - f0 - h * derivative).norm());
  }
  std::vector<double> orders;
  for (std::size_t k = 0; k + 1 < r.size(); ++k)
    if (r[k] > floor && r[k + 1] > floor) orders.push_back(std::log2(r[k] / r[k + 1]));
  if (report) {
    *report = "vector Taylor orders:";
    for (double o : orders) *report += " " + std::to_string(o);
  }
  if (orders.empty()) return std::numeric_limits<double>::infinity();
  std::vector<double> tail(
      orders.end() - std::min<std::ptrdiff_t>(3, static_cast<std::ptrdiff_t>(orders.size())),
      orders.end());
  std::sort(tail.begin(), tail.end());
  return tail[tail.size() / 2];
}

}  // namespace incise::test
