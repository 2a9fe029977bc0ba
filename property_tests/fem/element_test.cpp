/// Property tests of the tetrahedron kernels (tet_kernels.hpp; thesis (2.38), (3.4), (4.3),
/// (4.4)) for every registered material: element energy → force → tangent by central
/// differences with a step sweep and Taylor order, tangent symmetry, force balance, and the
/// det F ≤ 0 behaviour.

#include <incise/fem/tet_kernels.hpp>
#include <incise/fixtures/deformations.hpp>
#include <incise/fixtures/derivative_check.hpp>
#include <incise/material/material.hpp>
#include <incise_test/fd_check.hpp>
#include <incise_test/param_names.hpp>
#include <incise_test/seed.hpp>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>

namespace {

using incise::Mat3;
using incise::fem::TetKernel;
using incise::fem::TetReference;
using incise::material::Material;
using Mat34 = Eigen::Matrix<double, 3, 4>;
using Mat12 = Eigen::Matrix<double, 12, 12>;

incise::material::Parameters element_test_parameters() {
  incise::material::Parameters p;
  p.youngs_modulus = 3.0;
  p.poisson_ratio = 0.3;
  p.gamma = 0.4;
  return p;
}

/// A random, reasonably shaped, positively oriented reference tetrahedron (columns z1..z4):
/// corners moved by up to 0.25, volume > 0.05 (the unit corner tetrahedron has 1/6).
Mat34 random_tet(std::mt19937_64& rng) {
  return incise::fixtures::random_tetrahedron(rng, 0.25, 0.05);
}

/// Nodal displacements realizing the affine map x ↦ F x + t on the reference nodes.
Mat34 affine_displacement(const Mat34& z, const Mat3& f, const Eigen::Vector3d& t) {
  Mat34 x;
  for (int a = 0; a < 4; ++a) x.col(a) = (f - Mat3::Identity()) * z.col(a) + t;
  return x;
}

Mat34 random_direction(std::mt19937_64& rng) {
  return Mat34::NullaryExpr(
      [&]() { return std::uniform_real_distribution<double>(-1.0, 1.0)(rng); });
}

/// Step scale for a deformation: distances over which the kernels are smooth. Near inversion the
/// direction is pushed through F so that the element stays away from det F = 0.
struct ElementCase {
  Mat34 z;
  TetReference ref;
  Mat34 x;
  Mat34 d;
  double step;
  double condition;  ///< κ(F) = σ_max/σ_min
};

ElementCase make_setup(std::mt19937_64& rng, const Mat3& f) {
  ElementCase s;
  s.z = random_tet(rng);
  s.ref = incise::fem::make_tet_reference(s.z);
  s.x = affine_displacement(s.z, f, Eigen::Vector3d(0.1, -0.2, 0.3));
  // Direction: a random nodal field mapped through F (d_a = F·r_a), so the perturbed gradient
  // is F(I + t·R·Z⁻¹) and det F scales by det(I + tRZ⁻¹): smooth over |t| ≲ 0.1 whatever
  // det F is, even near inversion.
  s.d = f * random_direction(rng);
  s.step = 0.1;
  const Eigen::SelfAdjointEigenSolver<Mat3> es(f.transpose() * f);
  s.condition = std::sqrt(es.eigenvalues()(2) / es.eigenvalues()(0));
  return s;
}

class ElementProperty : public ::testing::TestWithParam<std::string> {
 protected:
  Material material() const { return Material(GetParam(), element_test_parameters()); }
};

template <class Fn>
void for_tet_model(const Material& m, Fn&& fn) {
  incise::material::visit_model(m.model_index(), [&](auto model) {
    fn(TetKernel<decltype(model), double>{});
    return 0;
  });
}

TEST_P(ElementProperty, ForceIsEnergyGradient_SweepAndTaylor) {
  INCISE_SEEDED_RNG(rng, 501);
  const Material m = material();
  for_tet_model(m, [&](auto k) {
    using K = decltype(k);
    for (const auto& def : incise::fixtures::deformation_families(rng)) {
      SCOPED_TRACE(def.family);
      const ElementCase s = make_setup(rng, def.f);
      Mat34 q;
      ASSERT_TRUE(K::forces(m.lame(), s.ref.z_inv, s.ref.b, s.x, q));
      const auto phi = [&](double t) {
        double w = 0.0;
        EXPECT_TRUE(K::energy(m.lame(), s.ref.z_inv, s.ref.volume, Mat34(s.x + t * s.d), w));
        return w;
      };
      const double dw = q.cwiseProduct(s.d).sum();
      const double unit = m.lame().mu * s.ref.volume * s.d.norm();
      const auto r = incise::fixtures::check_directional_derivative(phi, dw, s.step, unit);
      EXPECT_LE(r.best_relative_error, incise::test::kFdTolerance) << r.report;
      EXPECT_GE(r.taylor_order, incise::test::kMinTaylorOrder) << r.report;
    }
  });
}

TEST_P(ElementProperty, TangentIsForceDerivative_SweepAndTaylor) {
  INCISE_SEEDED_RNG(rng, 502);
  const Material m = material();
  for_tet_model(m, [&](auto k) {
    using K = decltype(k);
    for (const auto& def : incise::fixtures::deformation_families(rng)) {
      SCOPED_TRACE(def.family);
      const ElementCase s = make_setup(rng, def.f);
      const Mat34 w = random_direction(rng);  // contraction weight
      Mat34 q, q2, dq, dq2;
      Mat12 kt;
      ASSERT_TRUE(K::forces_and_product(m.lame(), s.ref.z_inv, s.ref.b, s.x, s.d, q, dq));
      ASSERT_TRUE(K::product(m.lame(), s.ref.z_inv, s.ref.b, s.x, s.d, dq2));
      ASSERT_TRUE(K::forces_and_tangent(m.lame(), s.ref.z_inv, s.ref.b, s.ref.volume, s.x, q2, kt));
      // Three routes to K_e·d and two to q agree to round-off of the tangent's scale.
      const Eigen::Map<const Eigen::Matrix<double, 12, 1>> dvec(s.d.data());
      const Eigen::Matrix<double, 12, 1> kd = kt * dvec;
      const double scale = kt.norm() * s.d.norm();
      // Closed form (built from F⁻ᵀ = F·C⁻¹) vs (4.4): round-off ~ (ops)·ε·κ(F)² of the scale.
      EXPECT_LE((Eigen::Map<const Eigen::Matrix<double, 12, 1>>(dq.data()) - kd).norm(),
                (1e-12 + 2e-14 * s.condition * s.condition) * scale);
      EXPECT_LE((dq2 - dq).norm(), 1e-12 * scale);
      EXPECT_LE((q2 - q).norm(), 1e-13 * (q.norm() + m.lame().mu * s.ref.volume));
      const auto phi = [&](double t) {
        Mat34 qt;
        EXPECT_TRUE(K::forces(m.lame(), s.ref.z_inv, s.ref.b, Mat34(s.x + t * s.d), qt));
        return qt.cwiseProduct(w).sum();
      };
      const double unit =
          scale * w.norm() / std::max(1.0, kt.norm() / (m.lame().mu * s.ref.volume)) + 1e-300;
      const auto r = incise::fixtures::check_directional_derivative(
          phi, dq.cwiseProduct(w).sum(), s.step, unit, (q.norm() + m.lame().mu) * w.norm());
      // Forces carry relative round-off ε_eff ≈ ε·κ(F)² (C⁻¹ = F⁻¹F⁻ᵀ); the best central
      // difference then errs by ~ε_eff^(2/3) (balancing h² truncation against ε_eff/h), times a
      // constant (20) for the larger third derivatives near inversion: 1e-5 at κ ≈ 10³.
      const double eps_eff = std::numeric_limits<double>::epsilon() * s.condition * s.condition;
      EXPECT_LE(r.best_relative_error,
                std::max(incise::test::kFdTolerance, 20.0 * std::pow(eps_eff, 2.0 / 3.0)))
          << r.report;
      EXPECT_GE(r.taylor_order, incise::test::kMinTaylorOrder) << r.report;
    }
  });
}

TEST_P(ElementProperty, TangentSymmetricForcesBalanced) {
  INCISE_SEEDED_RNG(rng, 503);
  const Material m = material();
  for_tet_model(m, [&](auto k) {
    using K = decltype(k);
    for (const auto& def : incise::fixtures::deformation_families(rng)) {
      SCOPED_TRACE(def.family);
      const ElementCase s = make_setup(rng, def.f);
      Mat34 q;
      Mat12 kt;
      ASSERT_TRUE(K::forces_and_tangent(m.lame(), s.ref.z_inv, s.ref.b, s.ref.volume, s.x, q, kt));
      // The tangent-only kernel (used by assembly) does the same arithmetic: identical bits.
      Mat12 kt_only;
      ASSERT_TRUE(K::tangent(m.lame(), s.ref.z_inv, s.ref.b, s.ref.volume, s.x, kt_only));
      EXPECT_TRUE((kt_only.array() == kt.array()).all());
      // Major symmetry of the tangent (hyperelastic): exact by construction up to round-off.
      EXPECT_LE((kt - kt.transpose()).norm(), 1e-13 * kt.norm());
      // f4 = −f1 − f2 − f3 (3.4): the element is in equilibrium.
      EXPECT_LE(q.rowwise().sum().norm(), 1e-14 * (q.norm() + 1e-300));
      // Rigid translations are in the kernel of K_e.
      Eigen::Matrix<double, 12, 1> t;
      for (int a = 0; a < 4; ++a) t.segment<3>(3 * a) = Eigen::Vector3d(0.3, -0.7, 1.1);
      EXPECT_LE((kt * t).norm(), 1e-13 * kt.norm() * t.norm());
    }
  });
}

TEST_P(ElementProperty, InvertedElementBehaviour) {
  INCISE_SEEDED_RNG(rng, 504);
  const Material m = material();
  for_tet_model(m, [&](auto k) {
    using K = decltype(k);
    const Mat34 z = random_tet(rng);
    const TetReference ref = incise::fem::make_tet_reference(z);
    const Mat3 reflect = Eigen::Vector3d(1.0, 1.0, -1.0).asDiagonal();
    const Mat34 x = affine_displacement(z, reflect, Eigen::Vector3d::Zero());
    Mat34 q;
    double w = 0.0;
    const bool ok_e = K::energy(m.lame(), ref.z_inv, ref.volume, x, w);
    const bool ok_f = K::forces(m.lame(), ref.z_inv, ref.b, x, q);
    if (m.linear_geometry() || m.defined_when_inverted()) {
      EXPECT_TRUE(ok_e && ok_f);
      EXPECT_TRUE(std::isfinite(w));
      if (!m.linear_geometry()) {
        // StVK: a mirrored tetrahedron is stress-free with zero energy (C = I) — the
        // unphysical behaviour §4.3.1 / Fig. 4.3 warns about.
        EXPECT_LE(std::abs(w), 1e-14 * m.lame().mu * ref.volume);
        EXPECT_LE(q.norm(), 1e-13 * m.lame().mu * ref.volume);
      }
    } else {
      EXPECT_FALSE(ok_e);
      EXPECT_FALSE(ok_f);
      EXPECT_TRUE(std::isinf(w) && w > 0);
    }
  });
}

INSTANTIATE_TEST_SUITE_P(AllRegistered, ElementProperty,
                         ::testing::ValuesIn(incise::material::registered_material_names()),
                         incise::test::material_param_name);

TEST(TetReference, VolumeAndInverseOfUnitTet) {
  Mat34 z;
  z << 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1;  // positively oriented: det[z2−z1, z3−z1, z4−z1] > 0
  const TetReference r = incise::fem::make_tet_reference(z);
  EXPECT_NEAR(r.volume, 1.0 / 6.0, 1e-16);  // exact in binary up to one rounding
  Mat3 zz;
  for (int a = 0; a < 3; ++a) zz.col(a) = z.col(a) - z.col(3);
  EXPECT_LE((r.z_inv * zz - Mat3::Identity()).norm(), 1e-15);
  EXPECT_LE((r.b - r.volume * r.z_inv.transpose()).norm(), 1e-16);
}

}  // namespace
