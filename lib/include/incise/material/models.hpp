#pragma once
/// \file models.hpp
/// The four hyperelastic models of thesis §4.3 as kernels templated on the scalar type (double
/// for computation, incise::Counted for flop counting), in the thesis' own terms:
/// W(C), S(C) = 2 ∂W/∂C and the stress derivative ∂S/∂C : H for a symmetric direction H.
///
/// Every model is a stateless struct with
/// - `kName` (registry name), `kLinearGeometry` (true: the argument C is the linearized
///   I + G + Gᵀ and T = S, eq. (2.22)), `kDefinedWhenInverted` (false: the energy has a log
///   term and det F ≤ 0 is reported as inverted with W = +∞), `kHasIsotropicTerms`,
///   `kHasInverseTerms` (which tangent coefficients can be non-zero, see TangentModuli);
/// - `energy(lame, C)` → W in J/m³ (+∞ when ι3 = det C ≤ 0 for log models);
/// - `stress(lame, C, state)` → S in Pa, filling `state` with quantities the derivative reuses
///   ("the calculations can be combined", §4.3);
/// - `stress_derivative(lame, state, H)` → ∂S/∂C : H (Pa), H symmetric;
/// - `moduli(lame, state)` → the coefficients of the common form of ∂S/∂C (TangentModuli).
///
/// All four fit dS = c1 tr(H) I + c2 H + c3 (C⁻¹:H) C⁻¹ + c4 C⁻¹·H·C⁻¹, which the element
/// tangent (fem/tet_kernels.hpp) exploits to build the 12×12 matrix in closed form.
///
/// Registering a model = appending it to `ModelList` at the end of this file; every property
/// test, verification table and benchmark iterates over `ModelList` / the registry.

#include <incise/material/parameters.hpp>

#include <Eigen/Core>
#include <cmath>
#include <limits>
#include <tuple>

/// Forces inlining of the kernel building blocks. The element kernels are instantiated for
/// several scalar types and models in one translation unit; without it GCC keeps helpers such as
/// the 3×3 product out of line, and returning 3×3 Lanes4 matrices through memory costs as much
/// as the arithmetic (measured: ElasticProblem::internal_forces 1.5× slower). No effect on
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

/// Quantities computed by `stress` and reused by `stress_derivative` / `moduli`.
template <class T>
struct MaterialState {
  Mat3T<T> c_inv;  ///< C⁻¹ (filled by models with inverse terms)
  T i1 = T(0);     ///< ι1 = tr C
  T i3 = T(0);     ///< ι3 = det C (models with inverse terms)
  T j = T(0);      ///< √ι3 (neo-Hookean)
  T e = T(0);      ///< exp(γ(ι1 − 3)) (Veronda-Westmann)
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

/// Inverse of a symmetric 3×3 matrix by cofactors; returns det C. 30 flops. Precondition:
/// det C ≠ 0 (callers check the sign of det C / det F first).
template <class T>
INCISE_KERNEL_INLINE T symmetric_inverse(const Mat3T<T>& c, Mat3T<T>& inv) {
  const T k00 = c(1, 1) * c(2, 2) - c(1, 2) * c(1, 2);
  const T k01 = c(0, 2) * c(1, 2) - c(0, 1) * c(2, 2);
  const T k02 = c(0, 1) * c(1, 2) - c(0, 2) * c(1, 1);
  const T k11 = c(0, 0) * c(2, 2) - c(0, 2) * c(0, 2);
  const T k12 = c(0, 1) * c(0, 2) - c(0, 0) * c(1, 2);
  const T k22 = c(0, 0) * c(1, 1) - c(0, 1) * c(0, 1);
  const T det = c(0, 0) * k00 + c(0, 1) * k01 + c(0, 2) * k02;
  const T r = T(1) / det;
  inv(0, 0) = k00 * r;
  inv(0, 1) = k01 * r;
  inv(0, 2) = k02 * r;
  inv(1, 1) = k11 * r;
  inv(1, 2) = k12 * r;
  inv(2, 2) = k22 * r;
  symmetrize_from_upper(inv);
  return det;
}

/// det of a symmetric 3×3 matrix (14 flops).
template <class T>
INCISE_KERNEL_INLINE T symmetric_det(const Mat3T<T>& c) {
  return c(0, 0) * (c(1, 1) * c(2, 2) - c(1, 2) * c(1, 2)) -
         c(0, 1) * (c(0, 1) * c(2, 2) - c(1, 2) * c(0, 2)) +
         c(0, 2) * (c(0, 1) * c(1, 2) - c(1, 1) * c(0, 2));
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

/// tr(C²) for symmetric C (14 flops).
template <class T>
INCISE_KERNEL_INLINE T symmetric_trace_square(const Mat3T<T>& c) {
  return c(0, 0) * c(0, 0) + c(1, 1) * c(1, 1) + c(2, 2) * c(2, 2) +
         T(2) * (c(0, 1) * c(0, 1) + c(0, 2) * c(0, 2) + c(1, 2) * c(1, 2));
}

template <class T>
INCISE_KERNEL_INLINE T infinity() {
  return T(std::numeric_limits<double>::infinity());
}

}  // namespace detail

/// St. Venant-Kirchhoff quadratic energy in E = (C − I)/2, shared by the linear and the StVK
/// models: W = μ E:E + (λ/2)(tr E)², S = 2μE + λ tr(E) I = μ(C − I) + (λ/2)(ι1 − 3) I,
/// ∂S/∂C : H = (λ/2) tr(H) I + μH (eqs. (2.22), (4.5)).
///
/// This W equals the thesis' (2.17) plus the constant 3μ/4 + 9λ/8, chosen so that W(I) = 0
/// (§4.3: "we arbitrarily set W = 0 for C = I"); S and the tangent are identical.
struct QuadraticEnergy {
  static constexpr bool kDefinedWhenInverted = true;
  static constexpr bool kHasIsotropicTerms = true;
  static constexpr bool kHasInverseTerms = false;

  template <class T>
  static INCISE_KERNEL_INLINE T energy(const Lame& p, const Mat3T<T>& c) {
    // E = (C − I)/2;  E:E = (tr C² − 2 tr C + 3)/4.
    const T i1 = c.trace();
    const T tre = T(0.5) * (i1 - T(3));
    const T ee = T(0.25) * (detail::symmetric_trace_square(c) - T(2) * i1 + T(3));
    return T(p.mu) * ee + T(0.5 * p.lambda) * tre * tre;
  }

  template <class T>
  static INCISE_KERNEL_INLINE Mat3T<T> stress(const Lame& p, const Mat3T<T>& c,
                                              MaterialState<T>& st) {
    st.i1 = c.trace();
    const T diag = T(0.5 * p.lambda) * (st.i1 - T(3)) - T(p.mu);
    Mat3T<T> s;
    s(0, 0) = T(p.mu) * c(0, 0) + diag;
    s(1, 1) = T(p.mu) * c(1, 1) + diag;
    s(2, 2) = T(p.mu) * c(2, 2) + diag;
    s(0, 1) = T(p.mu) * c(0, 1);
    s(0, 2) = T(p.mu) * c(0, 2);
    s(1, 2) = T(p.mu) * c(1, 2);
    detail::symmetrize_from_upper(s);
    return s;
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
/// linearized strain ε = (G + Gᵀ)/2, i.e. the kernels receive C_lin = I + G + Gᵀ and the
/// element uses T = S (linear geometry). Defined for every G (no inversion notion).
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
/// with J = √ι3 = |det F|. Undefined for det F ≤ 0 (ln J): the element reports inverted.
struct NeoHookean {
  static constexpr const char* kName = "neohookean";
  static constexpr bool kLinearGeometry = false;
  static constexpr bool kDefinedWhenInverted = false;
  static constexpr bool kHasIsotropicTerms = false;
  static constexpr bool kHasInverseTerms = true;

  template <class T>
  static INCISE_KERNEL_INLINE T energy(const Lame& p, const Mat3T<T>& c) {
    using std::log;
    using std::sqrt;
    const T i3 = detail::symmetric_det(c);
    if (!(i3 > T(0))) return detail::infinity<T>();
    const T j = sqrt(i3);
    const T jm1 = j - T(1);
    return T(0.5 * p.mu) * (c.trace() - T(3)) - T(0.5 * p.mu) * log(i3) +
           T(0.5 * p.lambda) * jm1 * jm1;
  }

  template <class T>
  static INCISE_KERNEL_INLINE Mat3T<T> stress(const Lame& p, const Mat3T<T>& c,
                                              MaterialState<T>& st) {
    using std::sqrt;
    st.i3 = detail::symmetric_inverse(c, st.c_inv);
    st.j = sqrt(st.i3);
    const T k = T(p.lambda) * (st.j - T(1)) * st.j - T(p.mu);
    Mat3T<T> s;
    s(0, 0) = k * st.c_inv(0, 0) + T(p.mu);
    s(1, 1) = k * st.c_inv(1, 1) + T(p.mu);
    s(2, 2) = k * st.c_inv(2, 2) + T(p.mu);
    s(0, 1) = k * st.c_inv(0, 1);
    s(0, 2) = k * st.c_inv(0, 2);
    s(1, 2) = k * st.c_inv(1, 2);
    detail::symmetrize_from_upper(s);
    return s;
  }

  template <class T>
  static INCISE_KERNEL_INLINE TangentModuli<T> moduli(const Lame& p, const MaterialState<T>& st) {
    TangentModuli<T> m;
    m.c3 = T(0.5 * p.lambda) * (T(2) * st.j - T(1)) * st.j;
    m.c4 = T(p.mu) - T(p.lambda) * (st.j - T(1)) * st.j;
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
/// For γ = 0 the exponential term is its limit 2μ(ι1 − 3)/2 (computed with expm1, so small γ
/// loses no digits). Its small-strain limit is linear elasticity with μ and
/// λ_eff = λ + 2μ(2γ − 1), not λ (the inconsistency the thesis remarks on). Undefined for
/// det F ≤ 0 (ln ι3 with the orientation lost): the element reports inverted.
struct VerondaWestmann {
  static constexpr const char* kName = "veronda-westmann";
  static constexpr bool kLinearGeometry = false;
  static constexpr bool kDefinedWhenInverted = false;
  static constexpr bool kHasIsotropicTerms = true;
  static constexpr bool kHasInverseTerms = true;

  template <class T>
  static INCISE_KERNEL_INLINE T energy(const Lame& p, const Mat3T<T>& c) {
    using std::expm1;
    using std::log;
    const T i3 = detail::symmetric_det(c);
    if (!(i3 > T(0))) return detail::infinity<T>();
    const T i1 = c.trace();
    const T i2 = T(0.5) * (i1 * i1 - detail::symmetric_trace_square(c));
    const T x = i1 - T(3);
    const T expo =
        p.gamma > 0.0 ? T(2.0 * p.mu / p.gamma) * expm1(T(p.gamma) * x) : T(2.0 * p.mu) * x;
    return T(0.5) * (expo - T(p.mu) * (i2 - T(3)) + T(0.5 * p.lambda) * (i3 - T(1) - log(i3)));
  }

  template <class T>
  static INCISE_KERNEL_INLINE Mat3T<T> stress(const Lame& p, const Mat3T<T>& c,
                                              MaterialState<T>& st) {
    using std::exp;
    st.i3 = detail::symmetric_inverse(c, st.c_inv);
    st.i1 = c.trace();
    st.e = p.gamma > 0.0 ? exp(T(p.gamma) * (st.i1 - T(3))) : T(1);
    const T diag = T(2.0 * p.mu) * st.e - T(p.mu) * st.i1;
    const T k = T(0.5 * p.lambda) * (st.i3 - T(1));
    Mat3T<T> s;
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j) s(i, j) = T(p.mu) * c(i, j) + k * st.c_inv(i, j);
    s(0, 0) += diag;
    s(1, 1) += diag;
    s(2, 2) += diag;
    detail::symmetrize_from_upper(s);
    return s;
  }

  template <class T>
  static INCISE_KERNEL_INLINE TangentModuli<T> moduli(const Lame& p, const MaterialState<T>& st) {
    TangentModuli<T> m;
    m.c1 = T(p.mu) * (T(2.0 * p.gamma) * st.e - T(1));
    m.c2 = T(p.mu);
    m.c3 = T(0.5 * p.lambda) * st.i3;
    m.c4 = T(-0.5 * p.lambda) * (st.i3 - T(1));
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
