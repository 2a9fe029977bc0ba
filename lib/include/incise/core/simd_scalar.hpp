#pragma once
/// \file simd_scalar.hpp
/// `Lanes4`: four doubles processed in lock step, a scalar type for the templated element
/// kernels (like `Counted`), so that one instantiation evaluates four elements at once with
/// SIMD instructions (GCC/Clang vector extension: two SSE2 operations per arithmetic operation
/// on x86-64 baseline, one AVX operation with -mavx).
///
/// Semantics: arithmetic and sqrt/exp/log/expm1 act lane-wise. Comparisons return a single
/// bool that is true only when the comparison holds in *every* lane; kernels use comparisons
/// only to detect inversion (`det F > 0`), so a false result means "some lane is inverted" and
/// callers re-evaluate those elements one by one with the double kernel. Values agree with the
/// double kernel to round-off (lane-wise IEEE operations; Eigen may order a reduction
/// differently for double, which vectorizes its own way).

#include <incise/core/scalar_traits.hpp>

#include <Eigen/Core>
#include <cmath>

namespace incise {

/// Four doubles in lock step (see file comment).
class Lanes4 {
 public:
  /// Aligned to 16 bytes, not 32: Eigen stores fixed-size matrices of Lanes4 16-byte aligned
  /// (GCC), so an AVX build of the kernels (fem, KernelIsa::kAvx) must use unaligned 256-bit
  /// loads; SSE2 code is the same either way.
  using Vec = double __attribute__((vector_size(32), aligned(16)));

  Lanes4() : v_{0.0, 0.0, 0.0, 0.0} {}
  /// Broadcast.
  Lanes4(double x) : v_{x, x, x, x} {}  // NOLINT(google-explicit-constructor)
  /// From explicit lanes.
  Lanes4(double a, double b, double c, double d) : v_{a, b, c, d} {}

  /// Lane i (0..3).
  double operator[](int i) const { return v_[i]; }
  /// Sets lane i (0..3).
  void set(int i, double x) { v_[i] = x; }

  friend Lanes4 operator+(const Lanes4& a, const Lanes4& b) { return from(a.v_ + b.v_); }
  friend Lanes4 operator-(const Lanes4& a, const Lanes4& b) { return from(a.v_ - b.v_); }
  friend Lanes4 operator*(const Lanes4& a, const Lanes4& b) { return from(a.v_ * b.v_); }
  friend Lanes4 operator/(const Lanes4& a, const Lanes4& b) { return from(a.v_ / b.v_); }
  friend Lanes4 operator-(const Lanes4& a) { return from(-a.v_); }
  friend Lanes4 operator+(const Lanes4& a) { return a; }
  Lanes4& operator+=(const Lanes4& b) { return *this = *this + b; }
  Lanes4& operator-=(const Lanes4& b) { return *this = *this - b; }
  Lanes4& operator*=(const Lanes4& b) { return *this = *this * b; }
  Lanes4& operator/=(const Lanes4& b) { return *this = *this / b; }

  friend bool operator<(const Lanes4& a, const Lanes4& b) { return all(a.v_ < b.v_); }
  friend bool operator>(const Lanes4& a, const Lanes4& b) { return all(a.v_ > b.v_); }
  friend bool operator<=(const Lanes4& a, const Lanes4& b) { return all(a.v_ <= b.v_); }
  friend bool operator>=(const Lanes4& a, const Lanes4& b) { return all(a.v_ >= b.v_); }
  friend bool operator==(const Lanes4& a, const Lanes4& b) { return all(a.v_ == b.v_); }
  friend bool operator!=(const Lanes4& a, const Lanes4& b) { return !(a == b); }

  friend Lanes4 sqrt(const Lanes4& a) {
    return map(a, [](double x) { return std::sqrt(x); });
  }
  friend Lanes4 exp(const Lanes4& a) {
    return map(a, [](double x) { return std::exp(x); });
  }
  friend Lanes4 expm1(const Lanes4& a) {
    return map(a, [](double x) { return std::expm1(x); });
  }
  friend Lanes4 log(const Lanes4& a) {
    return map(a, [](double x) { return std::log(x); });
  }
  /// |a| by clearing the sign bits (what std::abs does to each lane, NaN included), without
  /// taking the lanes apart.
  friend Lanes4 abs(const Lanes4& a) {
    constexpr long long kMagnitude = 0x7fffffffffffffffLL;
    const Mask m{kMagnitude, kMagnitude, kMagnitude, kMagnitude};
    return from((Vec)((Mask)a.v_ & m));
  }
  friend Lanes4 abs2(const Lanes4& a) { return a * a; }
  /// 2ᵏ exactly, for lanes holding integers k in [−1022, 1023] (precondition): the exponent
  /// field written from k (k + 1.5·2⁵² carries k in its low mantissa bits), integer operations
  /// only, so every instruction set gives the same bits.
  friend Lanes4 pow2_int(const Lanes4& k) {
    constexpr double kShift = 6755399441055744.0;  // 1.5·2⁵²
    const Vec shift{kShift, kShift, kShift, kShift};
    const Mask bias{1023, 1023, 1023, 1023};
    const Mask e = (((Mask)(k.v_ + shift) - (Mask)shift) + bias) << 52;
    return from((Vec)e);
  }

 private:
  using Mask = long long __attribute__((vector_size(32)));
  static Lanes4 from(const Vec& v) {
    Lanes4 r;
    r.v_ = v;
    return r;
  }
  static bool all(const Mask& m) { return m[0] && m[1] && m[2] && m[3]; }
  template <class Fn>
  static Lanes4 map(const Lanes4& a, Fn fn) {
    return Lanes4(fn(a.v_[0]), fn(a.v_[1]), fn(a.v_[2]), fn(a.v_[3]));
  }
  Vec v_;
};

}  // namespace incise

namespace Eigen {

/// Eigen traits for Lanes4 (real, signed; vectorization happens inside the scalar).
template <>
struct NumTraits<incise::Lanes4> : incise::RealScalarTraits<incise::Lanes4> {};

}  // namespace Eigen
