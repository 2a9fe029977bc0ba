#include <incise/delaunay/sweep.hpp>

#include <algorithm>
#include <cmath>

namespace incise::delaunay {
namespace {

double det3(const Vec3& x, const Vec3& y, const Vec3& z) {
  return x.dot(y.cross(z));
}

/// λ, µ of λD − µE = W by least squares; false when D ∥ E (singular normal equations) or the
/// residual exceeds the tolerance, or λ, µ lie outside [0, 1] beyond it.
bool solve_params(const Vec3& d, const Vec3& e, const Vec3& w, double& lambda, double& mu) {
  const double dd = d.dot(d), de = d.dot(e), ee = e.dot(e);
  const double den = dd * ee - de * de;
  if (!(den > kSweepTolerance * dd * ee)) return false;
  lambda = (ee * d.dot(w) - de * e.dot(w)) / den;
  mu = (de * d.dot(w) - dd * e.dot(w)) / den;
  const double scale = d.norm() + e.norm() + w.norm();
  if ((lambda * d - mu * e - w).norm() > 1e3 * kSweepTolerance * scale) return false;
  constexpr double kRange = 1e3 * kSweepTolerance;
  if (lambda < -kRange || lambda > 1 + kRange || mu < -kRange || mu > 1 + kRange) return false;
  lambda = std::clamp(lambda, 0.0, 1.0);
  mu = std::clamp(mu, 0.0, 1.0);
  return true;
}

}  // namespace

ScalpelSegment interpolate(const ScalpelSegment& from, const ScalpelSegment& to, double tau) {
  return {from.head + tau * (to.head - from.head), from.tail + tau * (to.tail - from.tail)};
}

const char* to_string(SweepCase c) {
  switch (c) {
    case SweepCase::kQuadratic: return "quadratic";
    case SweepCase::kLinear: return "linear";
    case SweepCase::kDoubleRoot: return "double root";
    case SweepCase::kCoplanar: return "coplanar";
  }
  return "?";
}

double segment_distance(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1, double& s,
                        double& u) {
  // Closest points of two segments: minimise |p0 + s d1 − q0 − u d2|² over the unit square
  // (the unconstrained minimiser clamped, then the other parameter re-projected and clamped).
  const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.dot(d1), e = d2.dot(d2), f = d2.dot(r);
  s = u = 0;
  if (a <= 0 && e <= 0) return r.norm();
  if (a <= 0) {
    u = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= 0) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), den = a * e - b * b;
      s = den > 0 ? std::clamp((b * f - c * e) / den, 0.0, 1.0) : 0.0;
      u = (b * s + f) / e;
      if (u < 0) {
        u = 0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (u > 1) {
        u = 1;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return (p0 + s * d1 - q0 - u * d2).norm();
}

double max_movement(const ScalpelSegment& scalpel, const Vec3& p, const Vec3& q) {
  double s, u;
  return segment_distance(scalpel.tail, scalpel.head, p, q, s, u);
}

SweepEdgeResult intersect_sweep_edge(const ScalpelSegment& from, const ScalpelSegment& to,
                                     const Vec3& a, const Vec3& b) {
  SweepEdgeResult out;
  const Vec3 e = a - b;
  // D(τ) = d0 + τ dd (scalpel direction T → H), W(τ) = w0 + τ dw (b − T(τ)).
  const Vec3 d0 = from.head - from.tail, dd = (to.head - to.tail) - d0;
  const Vec3 w0 = b - from.tail, dw = from.tail - to.tail;
  const double lmax = std::max(d0.norm(), (d0 + dd).norm());
  if (!(e.norm() > 0) || !(lmax > 0)) return out;
  // Eq. (5.1) reduced to coplanarity: det(D(τ), E, W(τ)) = c0 + c1 τ + c2 τ².
  const double c0 = det3(d0, e, w0), c1 = det3(dd, e, w0) + det3(d0, e, dw), c2 = det3(dd, e, dw);
  const double en = e.norm();
  const double s0 = d0.norm() * en * w0.norm(),
               s1 = dd.norm() * en * w0.norm() + d0.norm() * en * dw.norm(),
               s2 = dd.norm() * en * dw.norm();
  const double scale = s0 + s1 + s2;
  const double tol = kSweepTolerance * scale;
  auto add_root = [&](double tau) {
    constexpr double kRange = 1e3 * kSweepTolerance;
    if (!(tau >= -kRange && tau <= 1 + kRange)) return;
    tau = std::clamp(tau, 0.0, 1.0);
    double lambda, mu;
    if (solve_params(d0 + tau * dd, e, w0 + tau * dw, lambda, mu))
      out.hits.push_back({tau, lambda, mu});
  };
  if (std::abs(c0) <= tol && std::abs(c1) <= tol && std::abs(c2) <= tol) {
    out.kind = SweepCase::kCoplanar;
    auto gap = [&](double tau, double& lambda, double& mu) {
      const ScalpelSegment s = interpolate(from, to, tau);
      return segment_distance(s.tail, s.head, b, a, lambda, mu);
    };
    const double touch = 1e3 * kSweepTolerance * (lmax + en + w0.norm() + dw.norm());
    constexpr int kSamples = 64;
    double lambda = 0, mu = 0;
    double lo = 0;
    for (int k = 0; k <= kSamples; ++k) {
      const double tau = static_cast<double>(k) / kSamples;
      if (gap(tau, lambda, mu) > touch) {
        lo = tau;
        continue;
      }
      double hi = tau;
      if (k > 0)
        for (int i = 0; i < 60; ++i) {
          const double mid = 0.5 * (lo + hi);
          (gap(mid, lambda, mu) > touch ? lo : hi) = mid;
        }
      gap(hi, lambda, mu);
      // segment_distance's second parameter runs b → a: µ (weight of a) is that parameter.
      out.hits.push_back({hi, lambda, mu});
      break;
    }
    return out;
  }
  if (std::abs(c2) <= tol) {
    out.kind = SweepCase::kLinear;
    if (std::abs(c1) > tol) add_root(-c0 / c1);
    return out;
  }
  const double disc = c1 * c1 - 4 * c2 * c0;
  if (std::abs(disc) <= kSweepTolerance * (c1 * c1 + 4 * std::abs(c2 * c0))) {
    out.kind = SweepCase::kDoubleRoot;
    add_root(-c1 / (2 * c2));
    return out;
  }
  out.kind = SweepCase::kQuadratic;
  if (disc < 0) return out;
  // Roots without cancellation: q = −(c1 + sign(c1)√disc)/2, τ = q/c2 and c0/q.
  const double q = -0.5 * (c1 + std::copysign(std::sqrt(disc), c1));
  double r1 = q / c2, r2 = q != 0 ? c0 / q : r1;
  if (r2 < r1) std::swap(r1, r2);
  add_root(r1);
  if (r2 != r1) add_root(r2);
  return out;
}

}  // namespace incise::delaunay
