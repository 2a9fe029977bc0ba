#pragma once
/// \file models.hpp
/// The four hyperelastic models of thesis §4.3 as kernels templated on the scalar type (double
/// to compute, incise::Counted to count flops, incise::Lanes4 for four elements at once), in the
/// thesis' terms: W, S = 2 ∂W/∂C and the stress derivative ∂S/∂C : H for a symmetric direction
/// H — evaluated from the strain, not from C.
///
/// Small-strain accuracy: W, S and ∂S/∂C take a `Strain` (Green strain E = ½(C − I), or the
/// linearized ε, plus J − 1 = det F − 1 for models that need it) computed from the displacement
/// gradient G without forming I + G and subtracting I again (strain_from_gradient). Every
/// formula below is written in E, J − 1, C⁻¹ and expm1 / log1p remainders so that no O(1)
/// quantity is subtracted: W keeps its relative accuracy as ‖G‖ → 0 (it is O(‖G‖²)) and S its
/// (O(‖G‖)). The C-based entry points of material.hpp convert C first (strain_from_c), which
/// is as accurate as C itself.
///
/// Every model is a stateless struct with
/// - `kName` (registry name), `kLinearGeometry` (true: the strain is the linearized
///   ε = ½(G + Gᵀ) and T = S, eq. (2.22)), `kDefinedWhenInverted` (false: the energy has a log
///   term and det F ≤ 0 is reported as inverted with W = +∞), `kUsesJ` (needs
///   Strain::jm1), `kHasIsotropicTerms`, `kHasInverseTerms` (which tangent coefficients can be
///   non-zero, see TangentModuli);
/// - `energy(lame, strain)` → W in J/m³ (+∞ when J ≤ 0 for log models); `energy(lame,
///   strain, state)` the same value after `stress` filled `state` (reusing what it computed);
/// - `stress(lame, strain, state, S)` writes S in Pa, filling `state` with quantities the
///   derivative reuses ("the calculations can be combined", §4.3); S is an out-parameter so
///   that the element kernels write it in place (docs/fem_performance.md, "Issue 14");
/// - `stress_derivative(lame, state, H)` → ∂S/∂C : H (Pa), H symmetric;
/// - `moduli(lame, state)` → the coefficients of the common form of ∂S/∂C (TangentModuli).
///
/// All four fit dS = c1 tr(H) I + c2 H + c3 (C⁻¹:H) C⁻¹ + c4 C⁻¹·H·C⁻¹, which the element
/// tangent (fem/tet_kernels.hpp) exploits to build the 12×12 matrix in closed form.
///
/// Registering a model = appending it to `ModelList` at the end of this file; every property
/// test, verification table and benchmark iterates over `ModelList` / the registry.

#include <incise/core/simd_scalar.hpp>
#include <incise/material/parameters.hpp>

#include <Eigen/Core>
#include <cmath>
#include <limits>
#include <tuple>

/// Forces inlining of the kernel building blocks. The element kernels are instantiated for
/// several scalar types and models in one translation unit; without it GCC keeps helpers such as
/// the 3×3 product out of line, and returning 3×3 Lanes4 matrices through memory costs as much
/// as the arithmetic (the measurement: docs/fem_performance.md). No effect on
/// results. Not applied in sanitizer builds: instrumenting the fully inlined element loops takes
/// minutes and gigabytes per translation unit, and speed does not matter there.
#if defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define INCISE_SANITIZED_BUILD 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define INCISE_SANITIZED_BUILD 1
#endif
#if (defined(__GNUC__) || defined(__clang__)) && !defined(INCISE_SANITIZED_BUILD)
#define INCISE_KERNEL_INLINE inline __attribute__((always_inline))
#else
#define INCISE_KERNEL_INLINE inline
#endif

namespace incise::material {

/// 3×3 matrix over scalar T.
template <class T>
using Mat3T = Eigen::Matrix<T, 3, 3>;

/// The strain a model is evaluated at (thesis (2.21), (2.22)).
template <class T>
struct Strain {
  /// E = ½(C − I) = ½(G + Gᵀ + GᵀG) (Green-Lagrange), or ε = ½(G + Gᵀ) for the linear-geometry
  /// model; symmetric, dimensionless.
  Mat3T<T> e;
  /// J − 1 = det F − 1 (models with kUsesJ; −1 when det F ≤ 0 is known; 0 otherwise).
  T jm1 = T(0);
};

/// Quantities computed by `stress` and reused by `stress_derivative` / `moduli`.
template <class T>
struct MaterialState {
  Mat3T<T> c_inv;  ///< C⁻¹ (filled by models with inverse terms)
  T i3 = T(0);     ///< ι3 = det C = J² (models with inverse terms)
  T i3m1 = T(0);   ///< ι3 − 1 = (J − 1)(J + 1) (Veronda-Westmann)
  T j = T(0);      ///< J = √ι3 (neo-Hookean)
  T jm1 = T(0);    ///< J − 1 (neo-Hookean)
  T em1 = T(0);    ///< e^{γ(ι1 − 3)} − 1 (Veronda-Westmann)
  /// (eˣ − 1 − x)/x² at x = γ(ι1 − 3), the energy's remainder, when `stress` summed it on the
  /// way to em1 (has_rem; Veronda-Westmann on four lanes, see detail::expm1_stress): then
  /// energy(lame, strain, state) takes it instead of summing the series again.
  T rem = T(0);
  bool has_rem = false;
};

/// Coefficients of ∂S/∂C : H = c1 tr(H) I + c2 H + c3 (C⁻¹:H) C⁻¹ + c4 C⁻¹·H·C⁻¹ (Pa).
template <class T>
struct TangentModuli {
  T c1 = T(0), c2 = T(0), c3 = T(0), c4 = T(0);
};

namespace detail {

/// Upper triangle mirrored into the lower one (no arithmetic).
template <class T>
INCISE_KERNEL_INLINE void symmetrize_from_upper(Mat3T<T>& m) {
  m(1, 0) = m(0, 1);
  m(2, 0) = m(0, 2);
  m(2, 1) = m(1, 2);
}

/// Inverse of a symmetric 3×3 matrix from its cofactors and a given 1/det C (r), for callers
/// that know det C another way (Veronda-Westmann: ι3 = J² from J − 1, so the division does not
/// wait for the cofactors). 24 flops. Precondition: r = 1/det C, det C ≠ 0.
template <class T>
INCISE_KERNEL_INLINE void symmetric_inverse_given(const Mat3T<T>& c, const T& r, Mat3T<T>& inv) {
  inv(0, 0) = (c(1, 1) * c(2, 2) - c(1, 2) * c(1, 2)) * r;
  inv(0, 1) = (c(0, 2) * c(1, 2) - c(0, 1) * c(2, 2)) * r;
  inv(0, 2) = (c(0, 1) * c(1, 2) - c(0, 2) * c(1, 1)) * r;
  inv(1, 1) = (c(0, 0) * c(2, 2) - c(0, 2) * c(0, 2)) * r;
  inv(1, 2) = (c(0, 1) * c(0, 2) - c(0, 0) * c(1, 2)) * r;
  inv(2, 2) = (c(0, 0) * c(1, 1) - c(0, 1) * c(0, 1)) * r;
  symmetrize_from_upper(inv);
}

/// det of a symmetric 3×3 matrix (14 flops).
template <class T>
INCISE_KERNEL_INLINE T symmetric_det(const Mat3T<T>& c) {
  return c(0, 0) * (c(1, 1) * c(2, 2) - c(1, 2) * c(1, 2)) -
         c(0, 1) * (c(0, 1) * c(2, 2) - c(1, 2) * c(0, 2)) +
         c(0, 2) * (c(0, 1) * c(1, 2) - c(1, 1) * c(0, 2));
}

/// Second principal invariant ½((tr E)² − tr E²) of a symmetric 3×3 matrix: the sum of its
/// principal 2×2 minors (11 flops).
template <class T>
INCISE_KERNEL_INLINE T symmetric_second_invariant(const Mat3T<T>& e) {
  return (e(0, 0) * e(1, 1) - e(0, 1) * e(0, 1)) + (e(0, 0) * e(2, 2) - e(0, 2) * e(0, 2)) +
         (e(1, 1) * e(2, 2) - e(1, 2) * e(1, 2));
}

/// A·B for 3×3 matrices, written out (45 flops: the same operations as Eigen's product, in a
/// form compilers inline for every scalar type, including incise::Lanes4).
template <class T>
INCISE_KERNEL_INLINE Mat3T<T> mul(const Mat3T<T>& a, const Mat3T<T>& b) {
  Mat3T<T> r;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) r(i, j) = a(i, 0) * b(0, j) + a(i, 1) * b(1, j) + a(i, 2) * b(2, j);
  return r;
}

/// Aᵀ·B for 3×3 matrices (45 flops).
template <class T>
INCISE_KERNEL_INLINE Mat3T<T> mul_tn(const Mat3T<T>& a, const Mat3T<T>& b) {
  Mat3T<T> r;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) r(i, j) = a(0, i) * b(0, j) + a(1, i) * b(1, j) + a(2, i) * b(2, j);
  return r;
}

/// r = A·B for commuting symmetric A, B (then A·B is symmetric), upper triangle only
/// (30 flops).
template <class T>
INCISE_KERNEL_INLINE void symmetric_commuting_product(const Mat3T<T>& a, const Mat3T<T>& b,
                                                      Mat3T<T>& r) {
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) r(i, j) = a(i, 0) * b(0, j) + a(i, 1) * b(1, j) + a(i, 2) * b(2, j);
  symmetrize_from_upper(r);
}

/// A : B for symmetric A, B (12 flops).
template <class T>
INCISE_KERNEL_INLINE T symmetric_contract(const Mat3T<T>& a, const Mat3T<T>& b) {
  return a(0, 0) * b(0, 0) + a(1, 1) * b(1, 1) + a(2, 2) * b(2, 2) +
         T(2) * (a(0, 1) * b(0, 1) + a(0, 2) * b(0, 2) + a(1, 2) * b(1, 2));
}

/// A·H·A for symmetric A and H, computing the upper triangle only (75 flops).
template <class T>
INCISE_KERNEL_INLINE Mat3T<T> symmetric_sandwich(const Mat3T<T>& a, const Mat3T<T>& h) {
  const Mat3T<T> ah = mul(a, h);
  Mat3T<T> r;
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j)
      r(i, j) = ah(i, 0) * a(0, j) + ah(i, 1) * a(1, j) + ah(i, 2) * a(2, j);
  symmetrize_from_upper(r);
  return r;
}

/// tr(E²) = E : E for symmetric E (14 flops).
template <class T>
INCISE_KERNEL_INLINE T symmetric_trace_square(const Mat3T<T>& c) {
  return c(0, 0) * c(0, 0) + c(1, 1) * c(1, 1) + c(2, 2) * c(2, 2) +
         T(2) * (c(0, 1) * c(0, 1) + c(0, 2) * c(0, 2) + c(1, 2) * c(1, 2));
}

/// C = I + 2E for symmetric E (9 flops).
template <class T>
INCISE_KERNEL_INLINE Mat3T<T> right_cauchy_green(const Mat3T<T>& e) {
  Mat3T<T> c;
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) c(i, j) = T(2) * e(i, j);
  c(0, 0) += T(1);
  c(1, 1) += T(1);
  c(2, 2) += T(1);
  symmetrize_from_upper(c);
  return c;
}

template <class T>
INCISE_KERNEL_INLINE T infinity() {
  return T(std::numeric_limits<double>::infinity());
}

/// |x| below which x − ln(1 + x) is summed as a series (see x_minus_log1p).
constexpr double kLog1pSeriesLimit = 0.25;
/// |x| below which (eˣ − 1 − x)/x² is summed as a series (see expm1_remainder).
constexpr double kExpm1SeriesLimit = 0.5;

/// x − ln(1 + x) for x > −1 (+∞ at x = −1), to a few ulps relative for every x: the direct
/// difference loses ≈ 2ε/|x| relative as x → 0, so for |x| < ¼ it is summed from
/// ln(1 + x) = 2 atanh(s), s = x/(2 + x):  x − ln(1 + x) = s·x − 2s³ Σ_{k≥0} s^{2k}/(2k + 3)
/// (|s| ≤ 1/7, nine terms reach 1e-17 relative; 27 flops: the sum by Estrin's scheme in
/// z = s², pairs, then z², z⁴, z⁸ — a dependency chain of 4 multiply-adds where Horner's has 8,
/// for 3 more flops; issue 19, docs/solvers.md "Sixth pass"). Otherwise x − log1p(x) (51 flops;
/// ≈ 4ε/|x| relative, 16 ulps at the switch). The flops executed depend on the branch.
template <class T>
INCISE_KERNEL_INLINE T x_minus_log1p_series(const T& x) {
  const T s = x / (T(2) + x);
  const T z = s * s;
  const T z2 = z * z;
  const T z4 = z2 * z2;
  const T z8 = z4 * z4;
  const T p01 = T(1.0 / 3.0) + T(1.0 / 5.0) * z;
  const T p23 = T(1.0 / 7.0) + T(1.0 / 9.0) * z;
  const T p45 = T(1.0 / 11.0) + T(1.0 / 13.0) * z;
  const T p67 = T(1.0 / 15.0) + T(1.0 / 17.0) * z;
  const T q0 = p01 + p23 * z2;
  const T q1 = p45 + p67 * z2;
  const T sum = (q0 + q1 * z4) + T(1.0 / 19.0) * z8;
  return s * x - T(2) * (s * z) * sum;
}

template <class T>
INCISE_KERNEL_INLINE T x_minus_log1p(const T& x) {
  using std::abs;
  using std::log1p;
  if (abs(x) < T(kLog1pSeriesLimit)) return x_minus_log1p_series(x);
  return x - log1p(x);
}

/// (eˣ − 1 − x)/x² (→ ½ at x = 0), to a few ulps relative for every x: for |x| < ½ the series
/// Σ_{k≥0} xᵏ/(k + 2)! (14 terms reach 1e-17 relative; 29 flops), otherwise
/// (expm1(x) − x)/x² (53 flops; ≈ 8 ulps at the switch). The flops executed depend on the
/// branch. The series is summed by Estrin's scheme (pairs c_{2j} + c_{2j+1}x, then x², x⁴, x⁸):
/// a dependency chain of 4 multiply-adds where Horner's has 13, for 3 more flops — the chain
/// was ≈ 20 % of a four-lane Veronda–Westmann force sweep (issue 19, docs/solvers.md "Sixth
/// pass"). `x2` = x·x (the caller's, when it has it).
template <class T>
INCISE_KERNEL_INLINE T expm1_remainder_series(const T& x, const T& x2) {
  // c_k = 1/(k + 2)! for k = 0..13.
  constexpr double c[14] = {
      1.0 / 2,         1.0 / 6,          1.0 / 24,          1.0 / 120,          1.0 / 720,
      1.0 / 5040,      1.0 / 40320,      1.0 / 362880,      1.0 / 3628800,      1.0 / 39916800,
      1.0 / 479001600, 1.0 / 6227020800, 1.0 / 87178291200, 1.0 / 1307674368000};
  const T x4 = x2 * x2;
  const T x8 = x4 * x4;
  const T a0 = T(c[0]) + T(c[1]) * x;
  const T a1 = T(c[2]) + T(c[3]) * x;
  const T a2 = T(c[4]) + T(c[5]) * x;
  const T a3 = T(c[6]) + T(c[7]) * x;
  const T a4 = T(c[8]) + T(c[9]) * x;
  const T a5 = T(c[10]) + T(c[11]) * x;
  const T a6 = T(c[12]) + T(c[13]) * x;
  const T b0 = a0 + a1 * x2;
  const T b1 = a2 + a3 * x2;
  const T b2 = a4 + a5 * x2;
  return (b0 + b1 * x4) + (b2 + a6 * x4) * x8;
}

template <class T>
INCISE_KERNEL_INLINE T expm1_remainder_series(const T& x) {
  return expm1_remainder_series(x, T(x * x));
}

template <class T>
INCISE_KERNEL_INLINE T expm1_remainder(const T& x) {
  using std::abs;
  using std::expm1;
  if (abs(x) < T(kExpm1SeriesLimit)) return expm1_remainder_series(x);
  return (expm1(x) - x) / (x * x);
}

/// Lane-wise x_minus_log1p: each lane takes its own branch (Lanes4 comparisons hold only when
/// they hold in every lane, so the generic branch would send mixed blocks the inaccurate way).
/// When every lane takes the series (the common case), the series runs on all four lanes at
/// once: the same operations per lane, so the same bits as lane by lane.
INCISE_KERNEL_INLINE Lanes4 x_minus_log1p(const Lanes4& x) {
  if (abs(x) < Lanes4(kLog1pSeriesLimit)) return x_minus_log1p_series(x);
  Lanes4 r;
  for (int l = 0; l < 4; ++l) r.set(l, x_minus_log1p(x[l]));
  return r;
}

/// Lane-wise expm1_remainder (see x_minus_log1p(Lanes4)).
INCISE_KERNEL_INLINE Lanes4 expm1_remainder(const Lanes4& x) {
  if (abs(x) < Lanes4(kExpm1SeriesLimit)) return expm1_remainder_series(x);
  Lanes4 r;
  for (int l = 0; l < 4; ++l) r.set(l, expm1_remainder(x[l]));
  return r;
}

/// eˣ − 1 for the stress (VerondaWestmann): libm's std::expm1 for double (and the counted
/// scalar); for Lanes4 see the overload below. The three-argument form also reports the
/// energy's remainder (eˣ − 1 − x)/x² when it summed it on the way (never for this scalar form).
template <class T>
INCISE_KERNEL_INLINE T expm1_stress(const T& x) {
  using std::expm1;
  return expm1(x);
}

template <class T>
INCISE_KERNEL_INLINE T expm1_stress(const T& x, T& /*rem*/, bool& has_rem) {
  has_rem = false;
  return expm1_stress(x);
}

/// expm1_remainder(x) for the energy after the stress computed em1 = expm1_stress(x) (and
/// maybe the remainder): the same bits as expm1_remainder(x) — the series for |x| < ½, else
/// (em1 − x)/x² with em1 libm's expm1(x), which expm1_remainder would call again.
template <class T>
INCISE_KERNEL_INLINE T expm1_remainder_after(const T& x, const T& em1, const T& /*rem*/,
                                             bool /*has_rem*/) {
  using std::abs;
  if (abs(x) < T(kExpm1SeriesLimit)) return expm1_remainder_series(x);
  return (em1 - x) / (x * x);
}

/// |x| below which expm1_stress(Lanes4) takes the vector path (beyond it, or for NaN, every
/// lane calls std::expm1; eˣ overflows at 709.8).
constexpr double kExpm1VectorLimit = 700.0;
/// |x| below which round(x/ln 2) is 0 (< ½ ln 2 = 0.3466 with a margin for the rounding of
/// x/ln 2): expm1_stress(Lanes4) then skips the reduction, whose k would be 0.
constexpr double kExpm1NoReduction = 0.34;

/// eˣ − 1 on four lanes at once, without a libm call per lane (which cost ≈ 10 % of a
/// Veronda–Westmann sweep, issue 19): x = k ln 2 + r with k = round(x/ln 2) (|r| ≤ ½ ln 2;
/// ln 2 in two parts, Cody–Waite, so r is exact to the last bit of its rounding for |k| ≤ 1010),
/// eʳ − 1 = r + r²·expm1_remainder_series(r) (the series of the energy, accurate to 1e-17
/// relative for |r| < ½), then eˣ − 1 = (2ᵏ − 1) + 2ᵏ(eʳ − 1) (2ᵏ − 1 exact for 0 ≤ k ≤ 53;
/// k = 0 returns eʳ − 1 itself). Within 2 ulps of the exact value over the tested range
/// (measured 1.975 at x ≈ 0.387; test Expm1Lanes.WithinTwoUlpsOfLongDoubleReference; libm:
/// 0.78), and
/// the same bits in every lane position and instruction set (IEEE operations only, no FMA).
///
/// When |x| < kExpm1NoReduction in every lane (k = 0, r is x itself), the series summed here
/// is the energy's remainder expm1_remainder(x) bit for bit; the three-argument form hands it
/// back (has_rem) so that the fused gradient+energy sweep sums it once (issue 19).
INCISE_KERNEL_INLINE Lanes4 expm1_stress(const Lanes4& x, Lanes4& rem, bool& has_rem) {
  has_rem = false;
  if (!(abs(x) < Lanes4(kExpm1VectorLimit))) {  // also NaN lanes
    Lanes4 r;
    for (int l = 0; l < 4; ++l) r.set(l, std::expm1(x[l]));
    return r;
  }
  if (abs(x) < Lanes4(kExpm1NoReduction)) {
    // k = 0 in every lane: r = x, 2ᵏ = 1 and (2ᵏ − 1) + 2ᵏ(eʳ − 1) is eʳ − 1 — the value of
    // the general path below (up to the sign of a zero), without its reduction on the chain.
    const Lanes4 x2 = x * x;
    rem = expm1_remainder_series(x, x2);
    has_rem = true;
    return x + x2 * rem;
  }
  constexpr double kInvLn2 = 1.44269504088896338700e+00;
  constexpr double kLn2Hi = 6.93147180369123816490e-01;  // 32 significant bits: k·kLn2Hi exact
  constexpr double kLn2Lo = 1.90821492927058770002e-10;
  constexpr double kShift = 6755399441055744.0;  // 1.5·2⁵²: (y + kShift) − kShift rounds y
  const Lanes4 k = (x * Lanes4(kInvLn2) + Lanes4(kShift)) - Lanes4(kShift);
  const Lanes4 r = (x - k * Lanes4(kLn2Hi)) - k * Lanes4(kLn2Lo);
  const Lanes4 r2 = r * r;
  const Lanes4 em1_r = r + r2 * expm1_remainder_series(r, r2);
  const Lanes4 s = pow2_int(k);
  return (s - Lanes4(1)) + s * em1_r;
}

INCISE_KERNEL_INLINE Lanes4 expm1_stress(const Lanes4& x) {
  Lanes4 rem;
  bool has_rem = false;
  return expm1_stress(x, rem, has_rem);
}

/// expm1_remainder_after on four lanes: the stress' series when it had one (the same bits as
/// expm1_remainder(x): r = x, and the series of x with x² = x·x), else expm1_remainder(x) (the
/// vector em1 is not libm's, so it is not used for the other branch).
INCISE_KERNEL_INLINE Lanes4 expm1_remainder_after(const Lanes4& x, const Lanes4& /*em1*/,
                                                  const Lanes4& rem, bool has_rem) {
  return has_rem ? rem : expm1_remainder(x);
}

}  // namespace detail

/// Linearized strain ε = ½(G + Gᵀ) (thesis (2.22); 6 flops), written into `e` (in place, like
/// the other strain helpers: see `stress` in the file comment).
template <class T>
INCISE_KERNEL_INLINE void linear_strain(const Mat3T<T>& g, Mat3T<T>& e) {
  e(0, 0) = g(0, 0);
  e(1, 1) = g(1, 1);
  e(2, 2) = g(2, 2);
  e(0, 1) = T(0.5) * (g(0, 1) + g(1, 0));
  e(0, 2) = T(0.5) * (g(0, 2) + g(2, 0));
  e(1, 2) = T(0.5) * (g(1, 2) + g(2, 1));
  detail::symmetrize_from_upper(e);
}

/// Green strain E = ½(FᵀF − I) = ½(G + GᵀF) (GᵀF = Gᵀ + GᵀG) from G and F = I + G, upper
/// triangle (42 flops), written into `e`. No term of size 1 enters: E keeps relative accuracy
/// as G → 0.
template <class T>
INCISE_KERNEL_INLINE void green_strain(const Mat3T<T>& g, const Mat3T<T>& f, Mat3T<T>& e) {
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j)
      e(i, j) = T(0.5) * (g(i, j) + (g(0, i) * f(0, j) + g(1, i) * f(1, j) + g(2, i) * f(2, j)));
  detail::symmetrize_from_upper(e);
}

/// det(I + G) − 1 from G and F = I + G, by cofactors of F along its first row with the 1s taken
/// out: (1 + G00)(1 + a) − G01 c01 + G02 c02 − 1 with 1 + a the (1,1)–(2,2) minor of F
/// (18 flops; det F itself is 14). No term of size 1 enters.
template <class T>
INCISE_KERNEL_INLINE T det_minus_one(const Mat3T<T>& g, const Mat3T<T>& f) {
  const T a = (g(1, 1) + g(2, 2)) + (g(1, 1) * g(2, 2) - g(1, 2) * g(2, 1));
  const T c01 = g(1, 0) * f(2, 2) - g(1, 2) * g(2, 0);
  const T c02 = g(1, 0) * g(2, 1) - f(1, 1) * g(2, 0);
  return ((g(0, 0) + a) + g(0, 0) * a) - g(0, 1) * c01 + g(0, 2) * c02;
}

/// The strain of `Model` from the displacement gradient G and F = I + G (F unused for linear
/// geometry), written into `s`: what the element kernels evaluate. For kUsesJ models also
/// J − 1; the caller checks jm1 > −1 (det F > 0) before evaluating a log model.
template <class Model, class T>
INCISE_KERNEL_INLINE void strain_from_gradient(const Mat3T<T>& g, const Mat3T<T>& f, Strain<T>& s) {
  if constexpr (Model::kLinearGeometry) {
    linear_strain(g, s.e);
  } else {
    if constexpr (Model::kUsesJ) s.jm1 = det_minus_one(g, f);
    green_strain(g, f, s.e);
  }
}

/// The strain of `Model` from a right Cauchy-Green tensor C (for the linear-geometry model the
/// linearized I + G + Gᵀ), written into `s`: E = ½(C − I) and, for kUsesJ models,
/// J − 1 = (ι3 − 1)/(1 + √ι3) with ι3 − 1 = det(I + (C − I)) − 1 (−1 when ι3 ≤ 0). As accurate
/// as C is; the element kernels do not go through C.
template <class Model, class T>
INCISE_KERNEL_INLINE void strain_from_c(const Mat3T<T>& c, Strain<T>& s) {
  using std::sqrt;
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) s.e(i, j) = T(0.5) * (i == j ? c(i, i) - T(1) : c(i, j));
  detail::symmetrize_from_upper(s.e);
  if constexpr (Model::kUsesJ) {
    Mat3T<T> d = c;
    d(0, 0) -= T(1);
    d(1, 1) -= T(1);
    d(2, 2) -= T(1);
    const T i3m1 = det_minus_one(d, c);
    s.jm1 = i3m1 > T(-1) ? T(i3m1 / (T(1) + sqrt(T(1) + i3m1))) : T(-1);
  }
}

/// strain_from_c returning the strain (for callers off the hot path).
template <class Model, class T>
Strain<T> strain_from_c(const Mat3T<T>& c) {
  Strain<T> s;
  strain_from_c<Model>(c, s);
  return s;
}

/// St. Venant-Kirchhoff quadratic energy in E, shared by the linear and the StVK models:
/// W = μ E:E + (λ/2)(tr E)², S = 2μE + λ tr(E) I (= μ(C − I) + (λ/2)(ι1 − 3) I),
/// ∂S/∂C : H = (λ/2) tr(H) I + μH (eqs. (2.22), (4.5)). E here is ε for the linear model.
///
/// This W equals the thesis' (2.17) plus the constant 3μ/4 + 9λ/8, chosen so that W(I) = 0
/// (§4.3: "we arbitrarily set W = 0 for C = I"); S and the tangent are identical.
struct QuadraticEnergy {
  static constexpr bool kDefinedWhenInverted = true;
  static constexpr bool kUsesJ = false;
  static constexpr bool kHasIsotropicTerms = true;
  static constexpr bool kHasInverseTerms = false;

  template <class T>
  static INCISE_KERNEL_INLINE T energy(const Lame& p, const Strain<T>& s) {
    const T tre = s.e.trace();
    return T(p.mu) * detail::symmetric_trace_square(s.e) + T(0.5 * p.lambda) * tre * tre;
  }

  template <class T>
  static INCISE_KERNEL_INLINE T energy(const Lame& p, const Strain<T>& s, const MaterialState<T>&) {
    return energy(p, s);
  }

  template <class T>
  static INCISE_KERNEL_INLINE void stress(const Lame& p, const Strain<T>& s, MaterialState<T>&,
                                          Mat3T<T>& r) {
    const T diag = T(p.lambda) * s.e.trace();
    r(0, 0) = T(2.0 * p.mu) * s.e(0, 0) + diag;
    r(1, 1) = T(2.0 * p.mu) * s.e(1, 1) + diag;
    r(2, 2) = T(2.0 * p.mu) * s.e(2, 2) + diag;
    r(0, 1) = T(2.0 * p.mu) * s.e(0, 1);
    r(0, 2) = T(2.0 * p.mu) * s.e(0, 2);
    r(1, 2) = T(2.0 * p.mu) * s.e(1, 2);
    detail::symmetrize_from_upper(r);
  }

  template <class T>
  static INCISE_KERNEL_INLINE Mat3T<T> stress_derivative(const Lame& p, const MaterialState<T>&,
                                                         const Mat3T<T>& h) {
    const T d = T(0.5 * p.lambda) * h.trace();
    Mat3T<T> r;
    r(0, 0) = T(p.mu) * h(0, 0) + d;
    r(1, 1) = T(p.mu) * h(1, 1) + d;
    r(2, 2) = T(p.mu) * h(2, 2) + d;
    r(0, 1) = T(p.mu) * h(0, 1);
    r(0, 2) = T(p.mu) * h(0, 2);
    r(1, 2) = T(p.mu) * h(1, 2);
    detail::symmetrize_from_upper(r);
    return r;
  }

  template <class T>
  static INCISE_KERNEL_INLINE TangentModuli<T> moduli(const Lame& p, const MaterialState<T>&) {
    TangentModuli<T> m;
    m.c1 = T(0.5 * p.lambda);
    m.c2 = T(p.mu);
    return m;
  }
};

/// Linear elasticity (thesis (2.22), §3.1, §4.3.2): the quadratic energy above evaluated at the
/// linearized strain ε = ½(G + Gᵀ), and the element uses T = S (linear geometry). Defined for
/// every G (no inversion notion).
struct LinearElastic : QuadraticEnergy {
  static constexpr const char* kName = "linear";
  static constexpr bool kLinearGeometry = true;
};

/// St. Venant-Kirchhoff (thesis (2.17), (4.5)): the quadratic energy in the Green-Lagrange
/// strain E = (FᵀF − I)/2. Defined but unphysical for det F ≤ 0: W depends on C = FᵀF only,
/// so a reflected tetrahedron (F = diag(1,1,−1)) is stress-free and has W = 0 — nothing
/// resists inversion (thesis Fig. 4.3).
struct StVenantKirchhoff : QuadraticEnergy {
  static constexpr const char* kName = "stvk";
  static constexpr bool kLinearGeometry = false;
};

/// Compressible neo-Hookean (thesis (4.6)):
/// W = ½(μ(ι1 − 3) − μ ln ι3 + λ(√ι3 − 1)²) = μ/2 (ι1 − 3) − μ ln J + λ/2 (J − 1)²,
/// S = μ I + (λ(J − 1)J − μ) C⁻¹, ∂S/∂C : H = −(λ(J−1)J − μ) C⁻¹HC⁻¹ + λ/2 (2J−1)J (C⁻¹:H) C⁻¹,
/// with J = √ι3 = det F. Undefined for det F ≤ 0 (ln J): the element reports inverted.
///
/// Evaluated without cancellation, with I2, I3 the invariants of E and j1 = J − 1:
/// ι3 = (1 + j1)² = 1 + 2 tr E + 4 I2 + 8 I3 gives tr E − j1 = j1²/2 − 2 I2 − 4 I3, so
/// W = μ(j1²/2 − 2 I2 − 4 I3 + (j1 − ln(1 + j1))) + λ/2 j1² (every term O(‖E‖²));
/// S = (μ − λ J j1)(I − C⁻¹) + λ J j1 I with I − C⁻¹ = (2/ι3)(E + (2 I2 + 4 I3) I − 2 adj E)
/// (no O(1) term) and C⁻¹ = I − (I − C⁻¹).
struct NeoHookean {
  static constexpr const char* kName = "neohookean";
  static constexpr bool kLinearGeometry = false;
  static constexpr bool kDefinedWhenInverted = false;
  static constexpr bool kUsesJ = true;
  static constexpr bool kHasIsotropicTerms = false;
  static constexpr bool kHasInverseTerms = true;

  template <class T>
  static INCISE_KERNEL_INLINE T energy(const Lame& p, const Strain<T>& s) {
    if (!(s.jm1 > T(-1))) return detail::infinity<T>();
    const T& j1 = s.jm1;
    const T i2 = detail::symmetric_second_invariant(s.e);
    const T i3 = detail::symmetric_det(s.e);
    const T j1sq = j1 * j1;
    // μ(tr E − ln J) = μ((tr E − j1) + (j1 − ln(1 + j1))).
    const T dev = (T(0.5) * j1sq - T(2) * i2 - T(4) * i3) + detail::x_minus_log1p(j1);
    return T(p.mu) * dev + T(0.5 * p.lambda) * j1sq;
  }

  template <class T>
  static INCISE_KERNEL_INLINE T energy(const Lame& p, const Strain<T>& s, const MaterialState<T>&) {
    return energy(p, s);
  }

  template <class T>
  static INCISE_KERNEL_INLINE void stress(const Lame& p, const Strain<T>& s, MaterialState<T>& st,
                                          Mat3T<T>& r) {
    // With D = C − I = 2E: ι3 (I − C⁻¹) = ι3 I − adj C = D + (I2(D) + I3(D)) I − adj D, every
    // term O(‖E‖) or smaller. In E: h = ½ ι3 (I − C⁻¹) = E + (2 I2 + 4 I3) I − 2 adj E.
    const Mat3T<T>& e = s.e;
    const T a00 = e(1, 1) * e(2, 2) - e(1, 2) * e(1, 2);
    const T a11 = e(0, 0) * e(2, 2) - e(0, 2) * e(0, 2);
    const T a22 = e(0, 0) * e(1, 1) - e(0, 1) * e(0, 1);
    const T a01 = e(0, 2) * e(1, 2) - e(0, 1) * e(2, 2);
    const T a02 = e(0, 1) * e(1, 2) - e(0, 2) * e(1, 1);
    const T a12 = e(0, 1) * e(0, 2) - e(0, 0) * e(1, 2);
    const T i2 = (a00 + a11) + a22;
    const T i3 = e(0, 0) * a00 + e(0, 1) * a01 + e(0, 2) * a02;
    const T sd = T(2) * i2 + T(4) * i3;
    Mat3T<T> h;
    h(0, 0) = (e(0, 0) + sd) - T(2) * a00;
    h(1, 1) = (e(1, 1) + sd) - T(2) * a11;
    h(2, 2) = (e(2, 2) + sd) - T(2) * a22;
    h(0, 1) = e(0, 1) - T(2) * a01;
    h(0, 2) = e(0, 2) - T(2) * a02;
    h(1, 2) = e(1, 2) - T(2) * a12;
    st.jm1 = s.jm1;
    st.j = T(1) + s.jm1;
    st.i3 = st.j * st.j;
    const T r2 = T(2) / st.i3;  // I − C⁻¹ = r2·h
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j) st.c_inv(i, j) = -r2 * h(i, j);
    st.c_inv(0, 0) += T(1);
    st.c_inv(1, 1) += T(1);
    st.c_inv(2, 2) += T(1);
    detail::symmetrize_from_upper(st.c_inv);
    // S = μ(I − C⁻¹) + k C⁻¹ = (μ − k)(I − C⁻¹) + k I, k = λ J (J − 1).
    const T k = T(p.lambda) * st.j * st.jm1;
    const T a = (T(p.mu) - k) * r2;
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j) r(i, j) = a * h(i, j);
    r(0, 0) += k;
    r(1, 1) += k;
    r(2, 2) += k;
    detail::symmetrize_from_upper(r);
  }

  template <class T>
  static INCISE_KERNEL_INLINE TangentModuli<T> moduli(const Lame& p, const MaterialState<T>& st) {
    TangentModuli<T> m;
    m.c3 = T(0.5 * p.lambda) * (T(2) * st.j - T(1)) * st.j;
    m.c4 = T(p.mu) - T(p.lambda) * st.jm1 * st.j;
    return m;
  }

  template <class T>
  static INCISE_KERNEL_INLINE Mat3T<T> stress_derivative(const Lame& p, const MaterialState<T>& st,
                                                         const Mat3T<T>& h) {
    const TangentModuli<T> m = moduli(p, st);
    const T tr = m.c3 * detail::symmetric_contract(st.c_inv, h);
    const Mat3T<T> chc = detail::symmetric_sandwich(st.c_inv, h);
    Mat3T<T> r;
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j) r(i, j) = tr * st.c_inv(i, j) + m.c4 * chc(i, j);
    detail::symmetrize_from_upper(r);
    return r;
  }
};

/// Veronda-Westmann as specialised in thesis §4.3.4:
/// W = ½( (2μ/γ)(e^{γ(ι1−3)} − 1) − μ(ι2 − 3) + (λ/2)(ι3 − 1 − ln ι3) ), ι2 = ½(ι1² − tr C²),
/// S = (2μ e^{γ(ι1−3)} − μ ι1) I + μ C + (λ/2)(ι3 − 1) C⁻¹                       (4.7)
/// ∂S/∂C : H = μ(2γ e^{γ(ι1−3)} − 1) tr(H) I + μH
///             + (λ/2)(ι3 (C⁻¹:H) C⁻¹ − (ι3 − 1) C⁻¹HC⁻¹)                         (4.8)
/// Its small-strain limit is linear elasticity with μ and λ_eff = λ + 2μ(2γ − 1), not λ (the
/// inconsistency the thesis remarks on). Undefined for det F ≤ 0 (ln ι3 with the orientation
/// lost): the element reports inverted.
///
/// Evaluated without cancellation, with x = γ(ι1 − 3) = 2γ tr E, ι2 − 3 = 4 tr E + 4 I2 and
/// ι3 − 1 = (J − 1)(J + 1): the terms linear in tr E cancel exactly, leaving
/// W = 2μ tr E · x · (eˣ − 1 − x)/x² − 2μ I2 + (λ/4)((ι3 − 1) − ln(1 + (ι3 − 1)))
/// (for γ = 0 the first term is 0, the limit of (2μ/γ)(eˣ − 1) − 4μ tr E), and
/// S = 2μ(expm1(x) − tr E) I + 2μE + (λ/2)(ι3 − 1) C⁻¹.
struct VerondaWestmann {
  static constexpr const char* kName = "veronda-westmann";
  static constexpr bool kLinearGeometry = false;
  static constexpr bool kDefinedWhenInverted = false;
  static constexpr bool kUsesJ = true;
  static constexpr bool kHasIsotropicTerms = true;
  static constexpr bool kHasInverseTerms = true;

  template <class T>
  static INCISE_KERNEL_INLINE T energy(const Lame& p, const Strain<T>& s) {
    if (!(s.jm1 > T(-1))) return detail::infinity<T>();
    const T tre = s.e.trace();
    const T x = T(2.0 * p.gamma) * tre;
    return energy_terms(p, s, tre, x, detail::expm1_remainder(x), s.jm1 * (T(2) + s.jm1));
  }

  /// energy(lame, strain) after stress(lame, strain, st, ·): the same value, with ι3 − 1 and,
  /// when stress summed it (four lanes), the remainder (eˣ − 1 − x)/x² taken from st.
  template <class T>
  static INCISE_KERNEL_INLINE T energy(const Lame& p, const Strain<T>& s,
                                       const MaterialState<T>& st) {
    if (!(s.jm1 > T(-1))) return detail::infinity<T>();
    const T tre = s.e.trace();
    const T x = T(2.0 * p.gamma) * tre;
    return energy_terms(p, s, tre, x, detail::expm1_remainder_after(x, st.em1, st.rem, st.has_rem),
                        st.i3m1);
  }

  template <class T>
  static INCISE_KERNEL_INLINE void stress(const Lame& p, const Strain<T>& s, MaterialState<T>& st,
                                          Mat3T<T>& r) {
    st.i3m1 = s.jm1 * (T(2) + s.jm1);
    st.i3 = T(1) + st.i3m1;
    // C⁻¹ = adj C / ι3 with ι3 = J² from J − 1: the division waits for J only, not for C.
    detail::symmetric_inverse_given(detail::right_cauchy_green(s.e), T(T(1) / st.i3), st.c_inv);
    const T tre = s.e.trace();
    st.em1 =
        p.gamma > 0.0 ? T(detail::expm1_stress(T(2.0 * p.gamma) * tre, st.rem, st.has_rem)) : T(0);
    const T diag = T(2.0 * p.mu) * (st.em1 - tre);
    const T k = T(0.5 * p.lambda) * st.i3m1;
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j) r(i, j) = T(2.0 * p.mu) * s.e(i, j) + k * st.c_inv(i, j);
    r(0, 0) += diag;
    r(1, 1) += diag;
    r(2, 2) += diag;
    detail::symmetrize_from_upper(r);
  }

  template <class T>
  static INCISE_KERNEL_INLINE TangentModuli<T> moduli(const Lame& p, const MaterialState<T>& st) {
    TangentModuli<T> m;
    m.c1 = T(p.mu) * (T(2.0 * p.gamma) * (T(1) + st.em1) - T(1));
    m.c2 = T(p.mu);
    m.c3 = T(0.5 * p.lambda) * st.i3;
    m.c4 = T(-0.5 * p.lambda) * st.i3m1;
    return m;
  }

  template <class T>
  static INCISE_KERNEL_INLINE Mat3T<T> stress_derivative(const Lame& p, const MaterialState<T>& st,
                                                         const Mat3T<T>& h) {
    const TangentModuli<T> m = moduli(p, st);
    const T d = m.c1 * h.trace();
    const T tr = m.c3 * detail::symmetric_contract(st.c_inv, h);
    const Mat3T<T> chc = detail::symmetric_sandwich(st.c_inv, h);
    Mat3T<T> r;
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j) r(i, j) = m.c2 * h(i, j) + tr * st.c_inv(i, j) + m.c4 * chc(i, j);
    r(0, 0) += d;
    r(1, 1) += d;
    r(2, 2) += d;
    detail::symmetrize_from_upper(r);
    return r;
  }

 private:
  /// W from tr E, x = 2γ tr E, the remainder (eˣ − 1 − x)/x² and ι3 − 1 (the formula above).
  template <class T>
  static INCISE_KERNEL_INLINE T energy_terms(const Lame& p, const Strain<T>& s, const T& tre,
                                             const T& x, const T& rem, const T& i3m1) {
    return T(2.0 * p.mu) * tre * x * rem - T(2.0 * p.mu) * detail::symmetric_second_invariant(s.e) +
           T(0.25 * p.lambda) * detail::x_minus_log1p(i3m1);
  }
};

/// The registry: every model listed here is enrolled in the name registry (material.hpp), in
/// every material/element property test, in the flop table and in every benchmark.
using ModelList = std::tuple<LinearElastic, StVenantKirchhoff, NeoHookean, VerondaWestmann>;

/// Number of registered models.
constexpr int kNumModels = static_cast<int>(std::tuple_size_v<ModelList>);

namespace detail {
template <std::size_t I, class Fn>
decltype(auto) visit_model_impl(int index, Fn&& fn) {
  if constexpr (I + 1 == std::tuple_size_v<ModelList>) {
    return fn(std::tuple_element_t<I, ModelList>{});
  } else {
    if (index == static_cast<int>(I)) return fn(std::tuple_element_t<I, ModelList>{});
    return visit_model_impl<I + 1>(index, std::forward<Fn>(fn));
  }
}
}  // namespace detail

/// Calls fn(Model{}) for the model at `index` in ModelList (precondition 0 ≤ index <
/// kNumModels; the last model is used otherwise). All instantiations must return one type.
template <class Fn>
decltype(auto) visit_model(int index, Fn&& fn) {
  return detail::visit_model_impl<0>(index, std::forward<Fn>(fn));
}

}  // namespace incise::material
