#pragma once
/// \file tri_kernels.hpp
/// Linear plane-stress triangle kinematics and element kernels (thesis §6.3), templated on the
/// scalar type (double to compute, incise::Counted to count flops) and on the material model
/// (material/models.hpp, evaluated in plane stress by material/plane_stress.hpp).
///
/// Notation (the 2D analogue of (2.31)–(2.34)): reference nodes z1..z3,
/// Z = Σ_j (z_j − z3) ⊗ e_j (2×2), U = Σ_j (u_j − u3) ⊗ e_j, G = U·Z⁻¹, F = I + G,
/// T = F·S₂. With area A and thickness d the elastic nodal forces are the columns of
/// −A·d·T·Z⁻ᵀ for nodes 1, 2 and f3 = −f1 − f2. As for tetrahedra the kernels return the
/// internal force q = −f_el = ∂(A d W₂)/∂x, q_a = A d P g_a with g_a the a-th row of Z⁻¹ and
/// g3 = −g1 − g2. Element DOF order: node-major, 2a + i.
///
/// The strain is computed from G (E₂ = ½(G + GᵀF), ε₂ = ½(G + Gᵀ), J₂ − 1 = G00 + G11 +
/// G00 G11 − G01 G10), never from C. Every kernel returns the PlaneStressStatus of the
/// out-of-plane solve (kInverted: det F₂ ≤ 0 for a log model; outputs then untouched).
/// Z⁻¹ and B = A d Z⁻ᵀ are precomputed (TriReference) and not counted.

#include <incise/core/types.hpp>
#include <incise/material/plane_stress.hpp>

#include <Eigen/Core>

namespace incise::fem {

/// 2×2 double matrix.
using Mat2 = Eigen::Matrix2d;
template <class T>
using Mat2T = material::Mat2T<T>;
template <class T>
using Mat23T = Eigen::Matrix<T, 2, 3>;
template <class T>
using Mat6T = Eigen::Matrix<T, 6, 6>;

/// Per-element reference data of a plane-stress triangle: Z⁻¹, B = A·d·Z⁻ᵀ, the signed area
/// A = det[z2 − z1, z3 − z1]/2 = det Z/2 (m², > 0 counter-clockwise) and the thickness d (m).
struct TriReference {
  Mat2 z_inv = Mat2::Zero();  ///< Z⁻¹ (1/m)
  Mat2 b = Mat2::Zero();      ///< A·d·Z⁻ᵀ (m²); column a is A·d·g_a
  double area = 0.0;          ///< signed reference area A (m²)
  double volume = 0.0;        ///< A·d (m³)
};

/// Reference data of the triangle with vertices the columns of `x` (metres) and thickness
/// `thickness` (m). When the area is not positive, z_inv and b stay zero.
inline TriReference make_tri_reference(const Eigen::Matrix<double, 2, 3>& x, double thickness) {
  Mat2 z;
  for (int a = 0; a < 2; ++a) z.col(a) = x.col(a) - x.col(2);
  TriReference r;
  r.area = 0.5 * z.determinant();
  r.volume = r.area * thickness;
  if (r.area > 0.0) {
    r.z_inv = z.inverse();
    r.b = r.volume * r.z_inv.transpose();
  }
  return r;
}

/// Plane-stress element kernels for `Model` over scalar `T`.
template <class Model, class T>
struct TriKernel {
  using Adapter = material::PlaneStress<Model>;
  using Status = material::PlaneStressStatus;

  /// Kinematics and the plane-stress state shared by all kernels.
  struct State {
    Mat2T<T> f;  ///< F = I + G (identity for linear geometry)
    material::PlaneStressState<T> ps;
  };

  /// U from nodal displacements x (2×3): column a is x_a − x_3 (4 flops).
  static INCISE_KERNEL_INLINE Mat2T<T> differences(const Mat23T<T>& x) {
    Mat2T<T> u;
    for (int a = 0; a < 2; ++a)
      for (int i = 0; i < 2; ++i) u(i, a) = x(i, a) - x(i, 2);
    return u;
  }

  /// G, F, the in-plane strain and the plane-stress solve (material/plane_stress.hpp).
  static INCISE_KERNEL_INLINE Status kinematics(const material::Lame& p, const Mat2T<T>& z_inv,
                                                const Mat23T<T>& x, State& st) {
    const Mat2T<T> g = differences(x) * z_inv;
    Mat2T<T> e;
    T j2m1(0);
    if constexpr (Model::kLinearGeometry) {
      e(0, 0) = g(0, 0);
      e(1, 1) = g(1, 1);
      e(0, 1) = e(1, 0) = T(0.5) * (g(0, 1) + g(1, 0));
      st.f.setIdentity();
    } else {
      st.f = g;
      st.f(0, 0) += T(1);
      st.f(1, 1) += T(1);
      for (int i = 0; i < 2; ++i)
        for (int j = i; j < 2; ++j)
          e(i, j) = T(0.5) * (g(i, j) + (g(0, i) * st.f(0, j) + g(1, i) * st.f(1, j)));
      e(1, 0) = e(0, 1);
      if constexpr (Model::kUsesJ)
        j2m1 = (g(0, 0) + g(1, 1)) + (g(0, 0) * g(1, 1) - g(0, 1) * g(1, 0));
    }
    return Adapter::solve(p, e, j2m1, st.ps);
  }

  /// q (2×3) from the first Piola-Kirchhoff stress P (2×2): q_a = P·B e_a, q3 = −q1 − q2.
  static INCISE_KERNEL_INLINE void nodal_from_piola(const Mat2T<T>& piola, const Mat2T<T>& b,
                                                    Mat23T<T>& q) {
    const Mat2T<T> pb = piola * b;
    q.template leftCols<2>() = pb;
    for (int i = 0; i < 2; ++i) q(i, 2) = -(pb(i, 0) + pb(i, 1));
  }

  /// Element energy A·d·W₂ (J). On failure w = +∞.
  static INCISE_KERNEL_INLINE Status energy(const material::Lame& p, const Mat2T<T>& z_inv,
                                            const T& volume, const Mat23T<T>& x, T& w) {
    State st;
    const Status s = kinematics(p, z_inv, x, st);
    if (s != Status::kOk) {
      w = material::detail::infinity<T>();
      return s;
    }
    w = volume * Adapter::energy(p, st.ps);
    return s;
  }

  /// Internal nodal forces q = ∂(A d W₂)/∂x (N).
  static INCISE_KERNEL_INLINE Status forces(const material::Lame& p, const Mat2T<T>& z_inv,
                                            const Mat2T<T>& b, const Mat23T<T>& x, Mat23T<T>& q) {
    State st;
    const Status s = kinematics(p, z_inv, x, st);
    if (s == Status::kOk) nodal_from_piola(piola(st), b, q);
    return s;
  }

  /// Internal forces q and the element energy A·d·W₂ from one kinematics evaluation (the
  /// gradient with its energy in one sweep). On failure w = +∞ and q is untouched.
  static INCISE_KERNEL_INLINE Status forces_and_energy(const material::Lame& p,
                                                       const Mat2T<T>& z_inv, const Mat2T<T>& b,
                                                       const T& volume, const Mat23T<T>& x,
                                                       Mat23T<T>& q, T& w) {
    State st;
    const Status s = kinematics(p, z_inv, x, st);
    if (s != Status::kOk) {
      w = material::detail::infinity<T>();
      return s;
    }
    nodal_from_piola(piola(st), b, q);
    w = volume * Adapter::energy(p, st.ps);
    return s;
  }

  /// Matrix-free product dq = K_e·d (recomputes the kinematics at x).
  static INCISE_KERNEL_INLINE Status product(const material::Lame& p, const Mat2T<T>& z_inv,
                                             const Mat2T<T>& b, const Mat23T<T>& x,
                                             const Mat23T<T>& d, Mat23T<T>& dq) {
    State st;
    const Status s = kinematics(p, z_inv, x, st);
    if (s == Status::kOk) product_at(st, z_inv, b, d, dq);
    return s;
  }

  /// Forces and the 6×6 tangent K_e = ∂q/∂x, column by column as K_e·e_j (six products at one
  /// state).
  static INCISE_KERNEL_INLINE Status forces_and_tangent(const material::Lame& p,
                                                        const Mat2T<T>& z_inv, const Mat2T<T>& b,
                                                        const Mat23T<T>& x, Mat23T<T>& q,
                                                        Mat6T<T>& k) {
    State st;
    const Status s = kinematics(p, z_inv, x, st);
    if (s != Status::kOk) return s;
    nodal_from_piola(piola(st), b, q);
    for (int j = 0; j < 6; ++j) {
      Mat23T<T> d = Mat23T<T>::Zero();
      d(j % 2, j / 2) = T(1);
      Mat23T<T> dq;
      product_at(st, z_inv, b, d, dq);
      for (int r = 0; r < 6; ++r) k(r, j) = dq(r % 2, r / 2);
    }
    return s;
  }

 private:
  static INCISE_KERNEL_INLINE Mat2T<T> piola(const State& st) {
    if constexpr (Model::kLinearGeometry) return Adapter::stress(st.ps);
    return st.f * Adapter::stress(st.ps);
  }

  /// dC = FᵀdG + dGᵀF (linear: dG + dGᵀ), dS₂ condensed, dP = dG S₂ + F dS₂ (linear: dS₂).
  static INCISE_KERNEL_INLINE void product_at(const State& st, const Mat2T<T>& z_inv,
                                              const Mat2T<T>& b, const Mat23T<T>& d,
                                              Mat23T<T>& dq) {
    const Mat2T<T> dg = differences(d) * z_inv;
    Mat2T<T> dc;
    if constexpr (Model::kLinearGeometry) {
      dc(0, 0) = T(2) * dg(0, 0);
      dc(1, 1) = T(2) * dg(1, 1);
      dc(0, 1) = dc(1, 0) = dg(0, 1) + dg(1, 0);
      nodal_from_piola(Adapter::stress_derivative(st.ps, dc), b, dq);
    } else {
      const Mat2T<T> a = st.f.transpose() * dg;
      dc(0, 0) = T(2) * a(0, 0);
      dc(1, 1) = T(2) * a(1, 1);
      dc(0, 1) = dc(1, 0) = a(0, 1) + a(1, 0);
      const Mat2T<T> dp =
          dg * Adapter::stress(st.ps) + st.f * Adapter::stress_derivative(st.ps, dc);
      nodal_from_piola(dp, b, dq);
    }
  }
};

}  // namespace incise::fem
