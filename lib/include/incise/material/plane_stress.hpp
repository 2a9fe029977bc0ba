#pragma once
/// \file plane_stress.hpp
/// Plane-stress form of every registered model (thesis §6.3, (6.3)–(6.4)), templated on the
/// scalar type like models.hpp. A thin slab deforms in its plane with F = diag(F₂, q): the
/// in-plane gradient F₂ (2×2) and the out-of-plane stretch q, chosen per element so that the
/// out-of-plane stress vanishes, e₃·S·e₃ = 0. The 3D model is then evaluated at
/// E = diag(E₂, E₃₃), E₃₃ = ½(q² − 1), and
/// - W₂(E₂) = W(diag(E₂, E₃₃)) (J/m³), the energy per unit reference volume;
/// - S₂ = the in-plane 2×2 block of S (by the envelope theorem S₂ = 2∂W₂/∂C₂ since S₃₃ = 0);
/// - ∂S₂/∂C₂ : H = the in-plane block of ∂S/∂C : H minus the static condensation of E₃₃:
///   with the moduli c1..c4 of models.hpp, C⁻¹ = diag(C₂⁻¹, q⁻²),
///   a = c1 I + (c3/q²) C₂⁻¹ and k₃₃ = ∂S₃₃/∂C₃₃ = c1 + c2 + (c3 + c4)/q⁴,
///   ∂S₂/∂C₂ : H = c1 tr(H) I + c2 H + c3 (C₂⁻¹:H) C₂⁻¹ + c4 C₂⁻¹HC₂⁻¹ − a (a:H)/k₃₃.
///
/// E₃₃ solves S₃₃(E₃₃) = 0 by Newton from the linear plane-stress value
/// E₃₃⁰ = −λ/(λ + 2μ)·tr E₂ (dS₃₃/dE₃₃ = 2k₃₃). This start is the closed-form root for the
/// linear model (giving λ* = 2λμ/(λ + 2μ), docs/materials.md), for StVK (S₃₃ is linear in
/// E₃₃) and for neo-Hookean with ν = 0 (λ = 0: E₃₃ = 0, q = 1, thesis (6.4)); Newton then
/// stops after its first (rounding-sized) correction. Compressible neo-Hookean at ν > 0 and
/// Veronda-Westmann need iterations. A step that would make q² ≤ 0 is cut to half the
/// distance to q² = 0 (models with J only: the others are defined, if unphysical, for q² ≤ 0).
/// Converged when the correction falls below kNewtonTolerance · (|E₃₃| + ‖E₂‖_max) or stops
/// shrinking while S₃₃ already meets the acceptance test (the rounding floor), and then |S₃₃| ≤
/// kResidualTolerance · max(|S_ii|, (λ + 2μ)(|E₃₃| + ‖E₂‖_max)); otherwise kNotConverged (e.g.
/// Veronda-Westmann with λ = 0 at large stretch, whose root lies at q² < 0).
///
/// Strain inputs are cancellation-free (as models.hpp): E₂ from G₂, and J₂ − 1 = det F₂ − 1;
/// J − 1 = (J₂ − 1) + (q − 1) + (J₂ − 1)(q − 1) with q − 1 = 2E₃₃/(1 + q).

#include <incise/material/models.hpp>

#include <Eigen/Core>
#include <cmath>

namespace incise::material {

/// 2×2 matrix over scalar T.
template <class T>
using Mat2T = Eigen::Matrix<T, 2, 2>;

/// Outcome of solving e₃·S·e₃ = 0 for one element.
enum class PlaneStressStatus {
  kOk,           ///< E₃₃ found; the state is complete
  kInverted,     ///< det F₂ ≤ 0 (or q² ≤ 0) and the model is undefined there
  kNotConverged  ///< Newton did not converge in kMaxNewtonIterations (state unusable)
};

/// Name of a PlaneStressStatus ("ok", "inverted", "not-converged").
inline const char* to_string(PlaneStressStatus s) {
  switch (s) {
    case PlaneStressStatus::kOk: return "ok";
    case PlaneStressStatus::kInverted: return "inverted";
    case PlaneStressStatus::kNotConverged: return "not-converged";
  }
  return "?";
}

/// Everything the plane-stress evaluation computes once per element and reuses.
template <class T>
struct PlaneStressState {
  Strain<T> strain;           ///< the 3D strain diag(E₂, E₃₃) (and J − 1)
  MaterialState<T> m;         ///< the 3D model's state at that strain
  Mat3T<T> s;                 ///< the 3D S (S₃₃ ≈ 0 on success)
  TangentModuli<T> c;         ///< c1..c4 at the solution (filled by solve)
  int newton_iterations = 0;  ///< Newton corrections applied (≥ 1 on success)
};

/// Plane-stress adapter of a models.hpp `Model` (see file comment).
template <class Model>
struct PlaneStress {
  /// Newton iterations allowed for E₃₃.
  static constexpr int kMaxNewtonIterations = 40;
  /// Relative size of the last Newton correction at which E₃₃ counts as converged (Newton
  /// converges quadratically: the error left after a correction δ is O(δ²), far below ε).
  static constexpr double kNewtonTolerance = 1e-12;
  /// |S₃₃| relative to the largest stress term that an accepted solution may keep.
  static constexpr double kResidualTolerance = 1e-8;

  /// Solves S₃₃ = 0 for E₃₃ given the in-plane strain e2 (symmetric; for the linear model the
  /// linearized ε₂) and J₂ − 1 = det F₂ − 1 (ignored unless Model::kUsesJ), filling `st`.
  template <class T>
  static INCISE_KERNEL_INLINE PlaneStressStatus solve(const Lame& p, const Mat2T<T>& e2,
                                                      const T& j2m1, PlaneStressState<T>& st) {
    using std::abs;
    using std::sqrt;
    if constexpr (Model::kUsesJ) {
      if (!(j2m1 > T(-1))) return PlaneStressStatus::kInverted;
    }
    Mat3T<T>& e = st.strain.e;
    e(0, 0) = e2(0, 0);
    e(0, 1) = e2(0, 1);
    e(1, 1) = e2(1, 1);
    e(0, 2) = e(1, 2) = T(0);
    e(2, 2) = T(-p.lambda / (p.lambda + 2.0 * p.mu)) * (e2(0, 0) + e2(1, 1));
    if constexpr (Model::kUsesJ) {
      if (!(e(2, 2) > T(-0.5))) e(2, 2) = T(-0.25);
    }
    detail::symmetrize_from_upper(e);
    T scale = abs(e2(0, 0));
    if (abs(e2(1, 1)) > scale) scale = abs(e2(1, 1));
    if (abs(e2(0, 1)) > scale) scale = abs(e2(0, 1));
    T previous = detail::infinity<T>();
    for (int it = 1; it <= kMaxNewtonIterations; ++it) {
      if (!evaluate(p, j2m1, st)) return PlaneStressStatus::kInverted;
      st.c = Model::moduli(p, st.m);
      const T k33 = out_of_plane_modulus(st);
      T step = -st.s(2, 2) / (T(2) * k33);
      const T e33 = e(2, 2);
      if constexpr (Model::kUsesJ) {
        if (!(e33 + step > T(-0.5))) step = T(0.5) * (T(-0.5) - e33);
      }
      e(2, 2) = e33 + step;
      st.newton_iterations = it;
      // Converged: the correction is negligible, or it stopped shrinking at the rounding floor
      // (e.g. near inversion, where C⁻¹ amplifies the rounding of S₃₃): S₃₃ at this iterate
      // already meets the acceptance test below. A correction that does not shrink while S₃₃ is
      // still large is Newton converging from afar (the stiff exponential of Veronda-Westmann
      // at large stretch): iterate on.
      T size_now = T(p.lambda + 2.0 * p.mu) * (abs(e33) + scale);
      for (int i = 0; i < 3; ++i)
        if (abs(st.s(i, i)) > size_now) size_now = abs(st.s(i, i));
      const bool stalled =
          !(abs(step) < previous) && abs(st.s(2, 2)) <= T(kResidualTolerance) * size_now;
      previous = abs(step);
      if (stalled || !(abs(step) > T(kNewtonTolerance) * (abs(e(2, 2)) + scale))) {
        if (!evaluate(p, j2m1, st)) return PlaneStressStatus::kInverted;
        st.c = Model::moduli(p, st.m);
        // A correction that vanished against the q² > 0 bound is no root: S₃₃ must be at
        // rounding level against the stresses and moduli it is made of.
        T size = T(p.lambda + 2.0 * p.mu) * (abs(e(2, 2)) + scale);
        for (int i = 0; i < 3; ++i)
          if (abs(st.s(i, i)) > size) size = abs(st.s(i, i));
        if (!(abs(st.s(2, 2)) <= T(kResidualTolerance) * size))
          return PlaneStressStatus::kNotConverged;
        return PlaneStressStatus::kOk;
      }
    }
    return PlaneStressStatus::kNotConverged;
  }

  /// W₂ = W(diag(E₂, E₃₃)) in J/m³ after a successful solve.
  template <class T>
  static INCISE_KERNEL_INLINE T energy(const Lame& p, const PlaneStressState<T>& st) {
    return Model::energy(p, st.strain);
  }

  /// S₂, the in-plane block of S (Pa), after a successful solve.
  template <class T>
  static INCISE_KERNEL_INLINE Mat2T<T> stress(const PlaneStressState<T>& st) {
    Mat2T<T> s2;
    s2(0, 0) = st.s(0, 0);
    s2(0, 1) = s2(1, 0) = st.s(0, 1);
    s2(1, 1) = st.s(1, 1);
    return s2;
  }

  /// ∂S₂/∂C₂ : H (Pa) for symmetric 2×2 H, with E₃₃ condensed out (file comment).
  template <class T>
  static INCISE_KERNEL_INLINE Mat2T<T> stress_derivative(const PlaneStressState<T>& st,
                                                         const Mat2T<T>& h) {
    const TangentModuli<T>& c = st.c;
    const T trh = h(0, 0) + h(1, 1);
    // a = c1 I + (c3/q²) C₂⁻¹; C₂⁻¹ and 1/q² are the blocks of the 3D C⁻¹ (inverse-term
    // models only; the others have c3 = c4 = 0).
    Mat2T<T> a;
    T k33 = c.c1 + c.c2;
    Mat2T<T> r;
    if constexpr (Model::kHasInverseTerms) {
      const T iq2 = st.m.c_inv(2, 2);
      const T c3q = c.c3 * iq2;
      k33 = k33 + (c.c3 + c.c4) * (iq2 * iq2);
      Mat2T<T> ci;
      ci(0, 0) = st.m.c_inv(0, 0);
      ci(0, 1) = ci(1, 0) = st.m.c_inv(0, 1);
      ci(1, 1) = st.m.c_inv(1, 1);
      const T cih = ci(0, 0) * h(0, 0) + ci(1, 1) * h(1, 1) + T(2) * (ci(0, 1) * h(0, 1));
      const Mat2T<T> hc = h * ci;
      for (int i = 0; i < 2; ++i)
        for (int j = i; j < 2; ++j) {
          a(i, j) = c3q * ci(i, j);
          r(i, j) = c.c3 * cih * ci(i, j) + c.c4 * (ci(i, 0) * hc(0, j) + ci(i, 1) * hc(1, j));
        }
      a(0, 0) += c.c1;
      a(1, 1) += c.c1;
      r(0, 0) += c.c1 * trh;
      r(1, 1) += c.c1 * trh;
      for (int i = 0; i < 2; ++i)
        for (int j = i; j < 2; ++j) r(i, j) += c.c2 * h(i, j);
    } else {
      a.setZero();
      a(0, 0) = a(1, 1) = c.c1;
      for (int i = 0; i < 2; ++i)
        for (int j = i; j < 2; ++j) r(i, j) = c.c2 * h(i, j);
      r(0, 0) += c.c1 * trh;
      r(1, 1) += c.c1 * trh;
    }
    const T ah = (a(0, 0) * h(0, 0) + a(1, 1) * h(1, 1) + T(2) * (a(0, 1) * h(0, 1))) / k33;
    for (int i = 0; i < 2; ++i)
      for (int j = i; j < 2; ++j) r(i, j) -= a(i, j) * ah;
    r(1, 0) = r(0, 1);
    return r;
  }

 private:
  /// J − 1 from J₂ − 1 and E₃₃, then S at diag(E₂, E₃₃). False when q² ≤ 0 for a model
  /// undefined there.
  template <class T>
  static INCISE_KERNEL_INLINE bool evaluate(const Lame& p, const T& j2m1, PlaneStressState<T>& st) {
    using std::sqrt;
    if constexpr (Model::kUsesJ) {
      const T e33 = st.strain.e(2, 2);
      const T q2 = T(1) + T(2) * e33;
      if (!(q2 > T(0))) return false;
      const T qm1 = T(2) * e33 / (T(1) + sqrt(q2));
      st.strain.jm1 = (j2m1 + qm1) + j2m1 * qm1;
    }
    Model::stress(p, st.strain, st.m, st.s);
    return true;
  }

  /// k₃₃ = ∂S₃₃/∂C₃₃ = c1 + c2 + (c3 + c4)/q⁴ at the current state.
  template <class T>
  static INCISE_KERNEL_INLINE T out_of_plane_modulus(const PlaneStressState<T>& st) {
    T k = st.c.c1 + st.c.c2;
    if constexpr (Model::kHasInverseTerms) {
      const T iq2 = st.m.c_inv(2, 2);
      k = k + (st.c.c3 + st.c.c4) * (iq2 * iq2);
    }
    return k;
  }
};

}  // namespace incise::material
