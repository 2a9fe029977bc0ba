#include <incise/delaunay/predicates.hpp>

#include <cmath>
#include <limits>
#include <vector>

namespace incise::delaunay {
namespace {

// A floating-point expansion: the exact value is the sum of the components, which are
// non-overlapping and ordered by increasing magnitude, zeros removed (Shewchuk 1997, §2; the
// operations below are the textbook Grow-Expansion and its compositions, written for clarity
// rather than speed: they run only when the double-precision filter cannot decide).
using Expansion = std::vector<double>;

/// x + y = a + b exactly, x = fl(a + b) (Knuth's TwoSum; no ordering precondition).
inline void two_sum(double a, double b, double& x, double& y) {
  x = a + b;
  const double bv = x - a, av = x - bv;
  y = (a - av) + (b - bv);
}

/// x + y = a·b exactly, x = fl(a·b) (the FMA gives the rounding error of the product).
inline void two_product(double a, double b, double& x, double& y) {
  x = a * b;
  y = std::fma(a, b, -x);
}

/// e + b (Grow-Expansion with zero elimination).
Expansion grow(const Expansion& e, double b) {
  Expansion h;
  h.reserve(e.size() + 1);
  double q = b;
  for (const double ei : e) {
    double x, y;
    two_sum(q, ei, x, y);
    if (y != 0) h.push_back(y);
    q = x;
  }
  if (q != 0 || h.empty()) h.push_back(q);
  return h;
}

Expansion sum(Expansion e, const Expansion& f) {
  for (const double fj : f) e = grow(e, fj);
  return e;
}

Expansion negate(Expansion e) {
  for (double& x : e) x = -x;
  return e;
}

Expansion scale(const Expansion& e, double b) {
  Expansion h{0.0};
  for (const double ei : e) {
    double x, y;
    two_product(ei, b, x, y);
    h = grow(grow(h, y), x);
  }
  return h;
}

Expansion product(const Expansion& e, const Expansion& f) {
  Expansion h{0.0};
  for (const double fj : f) h = sum(h, scale(e, fj));
  return h;
}

/// a − b exactly, as an expansion of two components.
Expansion difference(double a, double b) {
  double x, y;
  two_sum(a, -b, x, y);
  return grow(Expansion{y}, x);
}

int sign(const Expansion& e) {
  const double top = e.back();  // the largest component decides (non-overlapping)
  return top > 0 ? 1 : (top < 0 ? -1 : 0);
}

constexpr double kEps = std::numeric_limits<double>::epsilon() / 2;  // 2⁻⁵³
constexpr double kOrientBound = (3.0 + 16.0 * kEps) * kEps;
constexpr double kIncircleBound = (10.0 + 96.0 * kEps) * kEps;

}  // namespace

int orient2d_exact(const Vec2& a, const Vec2& b, const Vec2& c) {
  // det[a − c, b − c] = (ax − cx)(by − cy) − (ay − cy)(bx − cx), same sign as det[b − a, c − a].
  const Expansion left = product(difference(a.x(), c.x()), difference(b.y(), c.y()));
  const Expansion right = product(difference(a.y(), c.y()), difference(b.x(), c.x()));
  return sign(sum(left, negate(right)));
}

int orient2d(const Vec2& a, const Vec2& b, const Vec2& c) {
  const double left = (a.x() - c.x()) * (b.y() - c.y());
  const double right = (a.y() - c.y()) * (b.x() - c.x());
  const double det = left - right;
  const double bound = kOrientBound * (std::abs(left) + std::abs(right));
  if (det > bound) return 1;
  if (-det > bound) return -1;
  return orient2d_exact(a, b, c);
}

int incircle_exact(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  const Expansion adx = difference(a.x(), d.x()), ady = difference(a.y(), d.y());
  const Expansion bdx = difference(b.x(), d.x()), bdy = difference(b.y(), d.y());
  const Expansion cdx = difference(c.x(), d.x()), cdy = difference(c.y(), d.y());
  const Expansion alift = sum(product(adx, adx), product(ady, ady));
  const Expansion blift = sum(product(bdx, bdx), product(bdy, bdy));
  const Expansion clift = sum(product(cdx, cdx), product(cdy, cdy));
  const Expansion bc = sum(product(bdx, cdy), negate(product(cdx, bdy)));
  const Expansion ca = sum(product(cdx, ady), negate(product(adx, cdy)));
  const Expansion ab = sum(product(adx, bdy), negate(product(bdx, ady)));
  return sign(sum(sum(product(alift, bc), product(blift, ca)), product(clift, ab)));
}

int incircle(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  const double adx = a.x() - d.x(), ady = a.y() - d.y();
  const double bdx = b.x() - d.x(), bdy = b.y() - d.y();
  const double cdx = c.x() - d.x(), cdy = c.y() - d.y();
  const double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy;
  const double cdxady = cdx * ady, adxcdy = adx * cdy;
  const double adxbdy = adx * bdy, bdxady = bdx * ady;
  const double alift = adx * adx + ady * ady;
  const double blift = bdx * bdx + bdy * bdy;
  const double clift = cdx * cdx + cdy * cdy;
  const double det =
      alift * (bdxcdy - cdxbdy) + blift * (cdxady - adxcdy) + clift * (adxbdy - bdxady);
  const double permanent = (std::abs(bdxcdy) + std::abs(cdxbdy)) * alift +
                           (std::abs(cdxady) + std::abs(adxcdy)) * blift +
                           (std::abs(adxbdy) + std::abs(bdxady)) * clift;
  const double bound = kIncircleBound * permanent;
  if (det > bound) return 1;
  if (-det > bound) return -1;
  return incircle_exact(a, b, c, d);
}

}  // namespace incise::delaunay
