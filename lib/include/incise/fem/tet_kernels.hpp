#pragma once
/// \file tet_kernels.hpp
/// Linear tetrahedron kinematics and element kernels (thesis §2.3, §3.1, §4.3), templated on
/// the scalar type (double to compute, incise::Counted to count flops) and on the material
/// model (material/models.hpp).
///
/// Notation (thesis (2.31)–(2.34), (3.4)): reference nodes z1..z4,
/// Z = Σ_j (z_j − z4) ⊗ e_j, displacement differences U = Σ_j (u_j − u4) ⊗ e_j,
/// G = U·Z⁻¹, F = I + G, C = FᵀF, T = F·S. With the volume v(τ) the elastic nodal forces are the
/// columns of −v(τ)·T·Z⁻ᵀ for nodes 1..3 and f4 = −f1 − f2 − f3 ((2.38), (3.4), (4.3)).
///
/// The material is evaluated at the strain computed from G, never from C or I + G + Gᵀ
/// (material::strain_from_gradient: E = ½(G + GᵀF), ε = ½(G + Gᵀ), J − 1 = det(I + G) − 1
/// expanded), so energy, forces and tangent keep their relative accuracy as G → 0.
///
/// The kernels return the *internal* force q = −f_el = ∂(v W)/∂x (the gradient of the element
/// energy), so that the global gradient of Π is Σ q − f_ext; q_a = v·P·g_a with g_a the a-th row
/// of Z⁻¹ (as a column) and g4 = −g1 − g2 − g3. Element DOF order: node-major, 3a + i.
///
/// Inputs that are fixed per element (Z⁻¹ and B = v·Z⁻ᵀ) are precomputed (TetReference) and not
/// counted; everything computed from the nodal displacements is counted, including U and f4.

#include <incise/core/types.hpp>
#include <incise/material/models.hpp>

#include <Eigen/Core>

namespace incise::fem {

template <class T>
using Mat3T = material::Mat3T<T>;
template <class T>
using Mat34T = Eigen::Matrix<T, 3, 4>;
template <class T>
using Mat12T = Eigen::Matrix<T, 12, 12>;
template <class T>
using Vec3T = Eigen::Matrix<T, 3, 1>;

/// Per-element reference data (thesis (2.32)): Z⁻¹, B = v(τ)·Z⁻ᵀ and the signed volume
/// v(τ) = det[z2 − z1, z3 − z1, z4 − z1] / 6 = −det Z / 6 (m³), positive for the mesh module's
/// positively oriented tetrahedra (mesh_data.hpp).
struct TetReference {
  Mat3 z_inv;     ///< Z⁻¹ (1/m)
  Mat3 b;         ///< v(τ)·Z⁻ᵀ (m²); column a is v(τ)·g_a
  double volume;  ///< signed reference volume v(τ) (m³); > 0 for a positively oriented tet
};

/// Reference data of the tetrahedron (x1, x2, x3, x4) (columns of `x`, metres). When the volume
/// is not positive, z_inv and b are left zero and only `volume` is meaningful.
inline TetReference make_tet_reference(const Eigen::Matrix<double, 3, 4>& x) {
  Mat3 z;
  for (int a = 0; a < 3; ++a) z.col(a) = x.col(a) - x.col(3);
  TetReference r;
  r.volume = -z.determinant() / 6.0;
  r.z_inv.setZero();
  r.b.setZero();
  if (r.volume > 0.0) {
    r.z_inv = z.inverse();
    r.b = r.volume * r.z_inv.transpose();
  }
  return r;
}

/// Element kernels for material model `Model` over scalar `T`.
template <class Model, class T>
struct TetKernel {
  /// Kinematic and stress quantities shared by force, product and tangent.
  struct State {
    Mat3T<T> f;                  ///< F = I + G (nonlinear geometry; unused for linear geometry)
    material::Strain<T> strain;  ///< E (linear geometry: ε), J − 1 for kUsesJ models
    Mat3T<T> s;                  ///< S
    material::MaterialState<T> m;
  };

  /// U from nodal displacements x (3×4): column a is x_a − x_4 (9 flops).
  static INCISE_KERNEL_INLINE Mat3T<T> differences(const Mat34T<T>& x) {
    Mat3T<T> u;
    for (int a = 0; a < 3; ++a)
      for (int i = 0; i < 3; ++i) u(i, a) = x(i, a) - x(i, 3);
    return u;
  }

  /// G, F (nonlinear geometry) and the strain from nodal displacements. Returns false when
  /// det F ≤ 0 and the model is undefined there (then the strain is incomplete).
  static INCISE_KERNEL_INLINE bool strain(const Mat3T<T>& z_inv, const Mat34T<T>& x, Mat3T<T>& f,
                                          material::Strain<T>& e) {
    static_assert(Model::kDefinedWhenInverted || Model::kUsesJ, "the inversion check needs J − 1");
    const Mat3T<T> g = material::detail::mul(differences(x), z_inv);
    if constexpr (!Model::kLinearGeometry) {
      f = g;
      f(0, 0) += T(1);
      f(1, 1) += T(1);
      f(2, 2) += T(1);
    }
    material::strain_from_gradient<Model>(g, f, e);
    if constexpr (!Model::kDefinedWhenInverted) return e.jm1 > T(-1);
    return true;
  }

  /// F (nonlinear geometry), the strain and S from nodal displacements. Returns false when
  /// det F ≤ 0 and the model is undefined there (then S is not computed).
  static INCISE_KERNEL_INLINE bool kinematics(const material::Lame& p, const Mat3T<T>& z_inv,
                                              const Mat34T<T>& x, State& st) {
    if (!strain(z_inv, x, st.f, st.strain)) return false;
    Model::stress(p, st.strain, st.m, st.s);
    return true;
  }

  /// q (3×4) from the first Piola-Kirchhoff stress P: q_a = P·B e_a, q4 = −Σ q_a (51 flops).
  static INCISE_KERNEL_INLINE void nodal_from_piola(const Mat3T<T>& piola, const Mat3T<T>& b,
                                                    Mat34T<T>& q) {
    const Mat3T<T> pb = material::detail::mul(piola, b);
    q.template leftCols<3>() = pb;
    for (int i = 0; i < 3; ++i) q(i, 3) = -(pb(i, 0) + pb(i, 1) + pb(i, 2));
  }

  /// Element energy v(τ)·W. Returns false (and +∞) when inverted.
  static INCISE_KERNEL_INLINE bool energy(const material::Lame& p, const Mat3T<T>& z_inv,
                                          const T& volume, const Mat34T<T>& x, T& w) {
    Mat3T<T> f;
    material::Strain<T> e;
    if (!strain(z_inv, x, f, e)) {
      w = material::detail::infinity<T>();
      return false;
    }
    w = volume * Model::energy(p, e);
    return true;
  }

  /// Internal nodal forces q (eq. (4.3) negated). Returns false when inverted (q untouched).
  static INCISE_KERNEL_INLINE bool forces(const material::Lame& p, const Mat3T<T>& z_inv,
                                          const Mat3T<T>& b, const Mat34T<T>& x, Mat34T<T>& q) {
    State st;
    if (!kinematics(p, z_inv, x, st)) return false;
    if constexpr (Model::kLinearGeometry) {
      nodal_from_piola(st.s, b, q);
    } else {
      nodal_from_piola(material::detail::mul(st.f, st.s), b, q);
    }
    return true;
  }

  /// Internal forces q and the element energy v(τ)·W from one kinematics evaluation (the
  /// gradient with its energy in one sweep). Returns false when inverted (q untouched, w = +∞).
  static INCISE_KERNEL_INLINE bool forces_and_energy(const material::Lame& p, const Mat3T<T>& z_inv,
                                                     const Mat3T<T>& b, const T& volume,
                                                     const Mat34T<T>& x, Mat34T<T>& q, T& w) {
    State st;
    if (!kinematics(p, z_inv, x, st)) {
      w = material::detail::infinity<T>();
      return false;
    }
    if constexpr (Model::kLinearGeometry) {
      nodal_from_piola(st.s, b, q);
    } else {
      nodal_from_piola(material::detail::mul(st.f, st.s), b, q);
    }
    w = volume * Model::energy(p, st.strain, st.m);
    return true;
  }

  /// Forces and the directional derivative (4.4) along nodal displacement direction d:
  /// dq = K_e·d. This is the pair Table 4.3 counts ("force" and "derivative").
  static INCISE_KERNEL_INLINE bool forces_and_product(const material::Lame& p,
                                                      const Mat3T<T>& z_inv, const Mat3T<T>& b,
                                                      const Mat34T<T>& x, const Mat34T<T>& d,
                                                      Mat34T<T>& q, Mat34T<T>& dq) {
    return forces_product_impl<false>(p, z_inv, b, T(0), x, d, q, dq, nullptr);
  }

  /// Forces, the element energy v(τ)·W and dq = K_e·d from one kinematics evaluation: what a
  /// Newton line search needs at each trial point (§4.4.2). False when inverted (w = +∞).
  static INCISE_KERNEL_INLINE bool forces_energy_and_product(const material::Lame& p,
                                                             const Mat3T<T>& z_inv,
                                                             const Mat3T<T>& b, const T& volume,
                                                             const Mat34T<T>& x, const Mat34T<T>& d,
                                                             Mat34T<T>& q, Mat34T<T>& dq, T& w) {
    return forces_product_impl<true>(p, z_inv, b, volume, x, d, q, dq, &w);
  }

 private:
  template <bool kEnergy>
  static INCISE_KERNEL_INLINE bool forces_product_impl(const material::Lame& p,
                                                       const Mat3T<T>& z_inv, const Mat3T<T>& b,
                                                       const T& volume, const Mat34T<T>& x,
                                                       const Mat34T<T>& d, Mat34T<T>& q,
                                                       Mat34T<T>& dq, T* w) {
    State st;
    if (!kinematics(p, z_inv, x, st)) {
      if constexpr (kEnergy) *w = material::detail::infinity<T>();
      return false;
    }
    if constexpr (kEnergy) *w = volume * Model::energy(p, st.strain, st.m);
    Mat3T<T> dg, dc, ds;
    derivative(p, z_inv, d, st, dg, dc, ds);
    if constexpr (Model::kLinearGeometry) {
      nodal_from_piola(st.s, b, q);
      nodal_from_piola(ds, b, dq);
    } else {
      nodal_from_piola(material::detail::mul(st.f, st.s), b, q);
      const Mat3T<T> dp = material::detail::mul(dg, st.s) + material::detail::mul(st.f, ds);
      nodal_from_piola(dp, b, dq);
    }
    return true;
  }

  /// Along nodal direction d at the state st: dG = D·Z⁻¹ (D the differences of d), dC, the
  /// derivative of C = FᵀF (FᵀdG + dGᵀF; linear geometry: dG + dGᵀ, twice dε) and
  /// dS = ∂S/∂C : dC (4.4).
  static INCISE_KERNEL_INLINE void derivative(const material::Lame& p, const Mat3T<T>& z_inv,
                                              const Mat34T<T>& d, const State& st, Mat3T<T>& dg,
                                              Mat3T<T>& dc, Mat3T<T>& ds) {
    dg = material::detail::mul(differences(d), z_inv);
    if constexpr (Model::kLinearGeometry) {
      for (int i = 0; i < 3; ++i)
        for (int j = i; j < 3; ++j) dc(i, j) = dg(i, j) + dg(j, i);
    } else {
      const Mat3T<T> a = material::detail::mul_tn(st.f, dg);
      for (int i = 0; i < 3; ++i)
        for (int j = i; j < 3; ++j) dc(i, j) = a(i, j) + a(j, i);
    }
    material::detail::symmetrize_from_upper(dc);
    ds = Model::stress_derivative(p, st.m, dc);
  }

 public:
  /// Matrix-free product only: dq = K_e·d (recomputes the kinematics; no forces). For the
  /// linear model K_e does not depend on x, so the kinematics at x are skipped.
  static INCISE_KERNEL_INLINE bool product(const material::Lame& p, const Mat3T<T>& z_inv,
                                           const Mat3T<T>& b, const Mat34T<T>& x,
                                           const Mat34T<T>& d, Mat34T<T>& dq) {
    State st;
    if constexpr (!Model::kLinearGeometry) {
      if (!kinematics(p, z_inv, x, st)) return false;
    }
    Mat3T<T> dg, dc, ds;
    derivative(p, z_inv, d, st, dg, dc, ds);
    if constexpr (Model::kLinearGeometry) {
      nodal_from_piola(ds, b, dq);
    } else {
      const Mat3T<T> dp = material::detail::mul(dg, st.s) + material::detail::mul(st.f, ds);
      nodal_from_piola(dp, b, dq);
    }
    return true;
  }

  /// The curvature dᵀK_e d along nodal direction d, without the nodal product K_e·d: with
  /// q_a = v·P·g_a, Σ_a d_a·(K_e d)_a = v·dP : dG, and with dP = dG·S + F·dS (4.4) and S, dS
  /// symmetric, dP : dG = S : (dGᵀdG) + ½ dS : dC (linear geometry: dP = dS, ½ dS : dC).
  /// What the secant line search needs (ElasticProblem::hessian_curvature); the same value as
  /// Σ_a d_a·(K_e d)_a up to rounding. Returns false when inverted.
  static INCISE_KERNEL_INLINE bool curvature(const material::Lame& p, const Mat3T<T>& z_inv,
                                             const T& volume, const Mat34T<T>& x,
                                             const Mat34T<T>& d, T& c) {
    State st;
    if constexpr (!Model::kLinearGeometry) {
      if (!kinematics(p, z_inv, x, st)) return false;
    }
    Mat3T<T> dg, dc, ds;
    derivative(p, z_inv, d, st, dg, dc, ds);
    T k = T(0.5) * material::detail::symmetric_contract(ds, dc);
    if constexpr (!Model::kLinearGeometry) {
      Mat3T<T> gg;  // dGᵀdG, upper triangle
      for (int i = 0; i < 3; ++i)
        for (int j = i; j < 3; ++j)
          gg(i, j) = dg(0, i) * dg(0, j) + dg(1, i) * dg(1, j) + dg(2, i) * dg(2, j);
      material::detail::symmetrize_from_upper(gg);
      k = material::detail::symmetric_contract(st.s, gg) + k;
    }
    c = volume * k;
    return true;
  }

  /// Forces and the full 12×12 element tangent K_e = ∂q/∂x, built in closed form from the
  /// tangent moduli (models.hpp): for nodes a, b with g = rows of Z⁻¹, p = F g, h = F⁻ᵀ g,
  ///   K_ab = v[(g_aᵀ(S + c4 C⁻¹) g_b) I + 2c1 p_a p_bᵀ + c2 (p_b p_aᵀ + (g_a·g_b) FFᵀ)
  ///            + 2c3 h_a h_bᵀ + c4 h_b h_aᵀ],
  /// (linear geometry: F = I and no geometric S term), K_ba = K_abᵀ, and node-4 blocks from
  /// g4 = −g1 − g2 − g3. Returns false when inverted.
  static INCISE_KERNEL_INLINE bool forces_and_tangent(const material::Lame& p,
                                                      const Mat3T<T>& z_inv, const Mat3T<T>& b,
                                                      const T& volume, const Mat34T<T>& x,
                                                      Mat34T<T>& q, Mat12T<T>& k) {
    return tangent_impl<true>(p, z_inv, b, volume, x, &q, k);
  }

  /// The 12×12 element tangent alone (as forces_and_tangent, without the forces: what the
  /// assembly of K(u) needs). Returns false when inverted.
  static INCISE_KERNEL_INLINE bool tangent(const material::Lame& p, const Mat3T<T>& z_inv,
                                           const Mat3T<T>& b, const T& volume, const Mat34T<T>& x,
                                           Mat12T<T>& k) {
    return tangent_impl<false>(p, z_inv, b, volume, x, nullptr, k);
  }

 private:
  template <bool kForces>
  static INCISE_KERNEL_INLINE bool tangent_impl(const material::Lame& p, const Mat3T<T>& z_inv,
                                                const Mat3T<T>& b, const T& volume,
                                                const Mat34T<T>& x, Mat34T<T>* q, Mat12T<T>& k) {
    State st;
    if (!kinematics(p, z_inv, x, st)) return false;
    if constexpr (kForces) {
      if constexpr (Model::kLinearGeometry) {
        nodal_from_piola(st.s, b, *q);
      } else {
        nodal_from_piola(material::detail::mul(st.f, st.s), b, *q);
      }
    }
    const material::TangentModuli<T> m = Model::moduli(p, st.m);
    const T& v = volume;
    // gt columns: g_a (a = 0..2).
    const Mat3T<T> gt = z_inv.transpose();
    Mat3T<T> pv, p1, p2, hv, h3, h4, bb, am;
    T k2(0), k4(0);
    if constexpr (Model::kHasIsotropicTerms) {
      const T k1 = T(2) * v * m.c1;
      k2 = v * m.c2;
      if constexpr (Model::kLinearGeometry) {
        pv = gt;
        bb.setZero();
        bb(0, 0) = bb(1, 1) = bb(2, 2) = k2;
      } else {
        pv = material::detail::mul(st.f, gt);
        for (int i = 0; i < 3; ++i)
          for (int j = i; j < 3; ++j)
            bb(i, j) =
                k2 * (st.f(i, 0) * st.f(j, 0) + st.f(i, 1) * st.f(j, 1) + st.f(i, 2) * st.f(j, 2));
        material::detail::symmetrize_from_upper(bb);
      }
      p1 = k1 * pv;
      p2 = k2 * pv;
    }
    if constexpr (Model::kHasInverseTerms) {
      const T k3 = T(2) * v * m.c3;
      k4 = v * m.c4;
      const Mat3T<T> f_inv_t = material::detail::mul(st.f, st.m.c_inv);
      hv = material::detail::mul(f_inv_t, gt);
      h3 = k3 * hv;
      h4 = k4 * hv;
    }
    // am = v S + k4 C⁻¹ (symmetric): the coefficient of the identity blocks.
    if constexpr (!Model::kLinearGeometry) {
      for (int i = 0; i < 3; ++i)
        for (int j = i; j < 3; ++j) {
          if constexpr (Model::kHasInverseTerms)
            am(i, j) = v * st.s(i, j) + k4 * st.m.c_inv(i, j);
          else
            am(i, j) = v * st.s(i, j);
        }
      material::detail::symmetrize_from_upper(am);
    }
    Mat3T<T> ag;  // column b: am·g_b
    if constexpr (!Model::kLinearGeometry) ag = material::detail::mul(am, gt);
    for (int a = 0; a < 3; ++a) {
      for (int bn = a; bn < 3; ++bn) {
        T gg(0);
        if constexpr (Model::kHasIsotropicTerms)
          gg = gt(0, a) * gt(0, bn) + gt(1, a) * gt(1, bn) + gt(2, a) * gt(2, bn);
        T s(0);
        if constexpr (!Model::kLinearGeometry)
          s = gt(0, a) * ag(0, bn) + gt(1, a) * ag(1, bn) + gt(2, a) * ag(2, bn);
        for (int i = 0; i < 3; ++i)
          for (int kk = 0; kk < 3; ++kk) {
            T e(0);
            bool first = true;
            auto acc = [&](const T& t) {
              e = first ? t : e + t;
              first = false;
            };
            if constexpr (Model::kHasIsotropicTerms) {
              acc(p1(i, a) * pv(kk, bn));
              acc(p2(i, bn) * pv(kk, a));
              acc(gg * bb(i, kk));
            }
            if constexpr (Model::kHasInverseTerms) {
              acc(h3(i, a) * hv(kk, bn));
              acc(h4(i, bn) * hv(kk, a));
            }
            if constexpr (!Model::kLinearGeometry) {
              if (i == kk) acc(s);
            }
            k(3 * a + i, 3 * bn + kk) = e;
            if (bn != a) k(3 * bn + kk, 3 * a + i) = e;
          }
      }
    }
    // Node-4 blocks: K_a4 = −(K_a1 + K_a2 + K_a3), K_4a = K_a4ᵀ, K_44 = −(K_14 + K_24 + K_34).
    for (int a = 0; a < 3; ++a)
      for (int i = 0; i < 3; ++i)
        for (int kk = 0; kk < 3; ++kk) {
          const T e = -((k(3 * a + i, kk) + k(3 * a + i, 3 + kk)) + k(3 * a + i, 6 + kk));
          k(3 * a + i, 9 + kk) = e;
          k(9 + kk, 3 * a + i) = e;
        }
    for (int i = 0; i < 3; ++i)
      for (int kk = 0; kk < 3; ++kk)
        k(9 + i, 9 + kk) = -((k(i, 9 + kk) + k(3 + i, 9 + kk)) + k(6 + i, 9 + kk));
    return true;
  }
};

}  // namespace incise::fem
