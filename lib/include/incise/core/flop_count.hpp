#pragma once
/// \file flop_count.hpp
/// A counting scalar: element kernels are templates on the scalar type, and instantiating them
/// once with `Counted` counts the floating-point operations they execute (docs/design.md
/// §1.4, thesis §4.2 and Table 4.3: "multiplications, divisions, sums and differences
/// were counted as one flop").
///
/// Charges (per executed operation, accumulated in a thread-local counter):
/// - binary + − × ÷ (also += −= ×= ÷=): 1 flop each;
/// - exp, expm1: 50 flops (the thesis measured "approximately 50 flops", §4.2);
/// - log, log1p: 50 flops (libm transcendentals of the same cost class as exp; the thesis gives
///   no figure, so we charge the same);
/// - sqrt: 1 flop (a single hardware instruction, like ÷);
/// - unary minus, abs, comparisons, copies and conversions: 0 flops (sign-bit operations and
///   branches are not arithmetic).
///
/// Counts are what the code executes, not what an ideal formula needs: Eigen's 3×3 product is
/// 45 flops (27 × and 18 +), a 3-vector dot product 5 flops.
///
/// `Counted` works with Eigen fixed-size matrices (NumTraits specialization below), so
/// `Eigen::Matrix<Counted, 3, 3>` can be multiplied, transposed and traced. Mixed expressions
/// with double scalars are allowed (`2.0 * Counted`, Eigen `Counted`-matrix × double).

#include <incise/core/scalar_traits.hpp>

#include <Eigen/Core>
#include <cmath>
#include <cstdint>

namespace incise {

/// The thread-local flop counter used by `Counted`. Reset it with `flop_counter() = 0`.
inline std::uint64_t& flop_counter() {
  thread_local std::uint64_t count = 0;
  return count;
}

/// Flops charged for one exp (thesis §4.2 measurement).
constexpr std::uint64_t kExpFlops = 50;
/// Flops charged for one log or log1p (same cost class as exp; see file comment).
constexpr std::uint64_t kLogFlops = 50;
/// Flops charged for one sqrt (one hardware instruction).
constexpr std::uint64_t kSqrtFlops = 1;

/// A double that counts the arithmetic done with it (see file comment for the charges).
class Counted {
 public:
  Counted() = default;
  /// Implicit from double: constants in kernels are free.
  Counted(double v) : v_(v) {}  // NOLINT(google-explicit-constructor)
  /// The wrapped value.
  double value() const { return v_; }
  explicit operator double() const { return v_; }

  friend Counted operator+(Counted a, Counted b) { return count(a.v_ + b.v_, 1); }
  friend Counted operator-(Counted a, Counted b) { return count(a.v_ - b.v_, 1); }
  friend Counted operator*(Counted a, Counted b) { return count(a.v_ * b.v_, 1); }
  friend Counted operator/(Counted a, Counted b) { return count(a.v_ / b.v_, 1); }
  friend Counted operator-(Counted a) { return Counted(-a.v_); }
  friend Counted operator+(Counted a) { return a; }
  Counted& operator+=(Counted b) { return *this = *this + b; }
  Counted& operator-=(Counted b) { return *this = *this - b; }
  Counted& operator*=(Counted b) { return *this = *this * b; }
  Counted& operator/=(Counted b) { return *this = *this / b; }

  friend bool operator<(Counted a, Counted b) { return a.v_ < b.v_; }
  friend bool operator>(Counted a, Counted b) { return a.v_ > b.v_; }
  friend bool operator<=(Counted a, Counted b) { return a.v_ <= b.v_; }
  friend bool operator>=(Counted a, Counted b) { return a.v_ >= b.v_; }
  friend bool operator==(Counted a, Counted b) { return a.v_ == b.v_; }
  friend bool operator!=(Counted a, Counted b) { return a.v_ != b.v_; }

  friend Counted exp(Counted a) { return count(std::exp(a.v_), kExpFlops); }
  friend Counted expm1(Counted a) { return count(std::expm1(a.v_), kExpFlops); }
  friend Counted log(Counted a) { return count(std::log(a.v_), kLogFlops); }
  friend Counted log1p(Counted a) { return count(std::log1p(a.v_), kLogFlops); }
  friend Counted sqrt(Counted a) { return count(std::sqrt(a.v_), kSqrtFlops); }
  friend Counted abs(Counted a) { return Counted(std::abs(a.v_)); }
  friend Counted abs2(Counted a) { return a * a; }
  friend bool isfinite(Counted a) { return std::isfinite(a.v_); }
  friend bool isnan(Counted a) { return std::isnan(a.v_); }
  friend bool isinf(Counted a) { return std::isinf(a.v_); }

 private:
  static Counted count(double v, std::uint64_t flops) {
    flop_counter() += flops;
    return Counted(v);
  }
  double v_ = 0.0;
};

/// The plain double value of a scalar (identity for double, value() for Counted).
inline double scalar_value(double x) {
  return x;
}
/// \overload
inline double scalar_value(Counted x) {
  return x.value();
}

/// RAII helper: counts the flops executed while it is alive (restores the outer count).
class FlopScope {
 public:
  FlopScope() : saved_(flop_counter()) { flop_counter() = 0; }
  ~FlopScope() { flop_counter() += saved_; }
  FlopScope(const FlopScope&) = delete;
  FlopScope& operator=(const FlopScope&) = delete;
  /// Flops counted since construction.
  std::uint64_t flops() const { return flop_counter(); }

 private:
  std::uint64_t saved_;
};

}  // namespace incise

namespace Eigen {

/// Eigen traits for the counting scalar: a real, signed, non-integer type of double precision.
template <>
struct NumTraits<incise::Counted> : incise::RealScalarTraits<incise::Counted> {};

/// Counted ⊗ double mixes to Counted (so `Matrix<Counted,3,3> * 2.0` compiles).
template <typename BinaryOp>
struct ScalarBinaryOpTraits<incise::Counted, double, BinaryOp> {
  using ReturnType = incise::Counted;
};
/// double ⊗ Counted mixes to Counted.
template <typename BinaryOp>
struct ScalarBinaryOpTraits<double, incise::Counted, BinaryOp> {
  using ReturnType = incise::Counted;
};

}  // namespace Eigen
