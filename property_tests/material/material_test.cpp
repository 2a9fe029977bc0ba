/// Property tests of the material models (thesis §2.1, §4.3; models.hpp), run automatically for
/// every model in the registry: derivative checks S vs W and ∂S/∂C:H vs S (central-difference
/// sweep + Taylor order), invariance, symmetry, stress-free reference, small-strain agreement
/// with the linear model, closed-form homogeneous states, det F ≤ 0 behaviour, parameters.

#include <incise/core/error.hpp>
#include <incise/fixtures/deformations.hpp>
#include <incise/fixtures/derivative_check.hpp>
#include <incise/material/material.hpp>
#include <incise_test/fd_check.hpp>
#include <incise_test/param_names.hpp>
#include <incise_test/seed.hpp>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <random>

namespace {

using incise::Mat3;
using incise::fixtures::check_directional_derivative;
using incise::fixtures::deformation_families;
using incise::fixtures::random_matrix;
using incise::fixtures::random_rotation;
using incise::fixtures::random_symmetric;
using incise::material::Material;
using incise::material::Parameters;

Parameters test_parameters() {
  Parameters p;
  p.youngs_modulus = 3.0;
  p.poisson_ratio = 0.3;
  p.gamma = 0.4;
  p.density = 1.0;
  return p;
}

/// Smallest eigenvalue of C = FᵀF (the distance to the boundary of SPD matrices).
double min_eig_c(const Mat3& f) {
  Eigen::SelfAdjointEigenSolver<Mat3> es(f.transpose() * f);
  return es.eigenvalues()(0);
}

/// Fᵀ Ĥ F (or Ĥ for the linear-geometry model, whose C is not FᵀF).
Mat3 pullback_direction(const Material& m, const Mat3& f, const Mat3& hat) {
  if (m.linear_geometry()) return hat;
  return f.transpose() * hat * f;
}

class MaterialProperty : public ::testing::TestWithParam<std::string> {
 protected:
  Material material() const { return Material(GetParam(), test_parameters()); }
  /// The C at which a model is evaluated for a deformation F: FᵀF, or the linearized strain
  /// I + G + Gᵀ for the linear-geometry model.
  static Mat3 c_of(const Material& m, const Mat3& f) {
    if (m.linear_geometry()) {
      const Mat3 g = f - Mat3::Identity();
      return Mat3::Identity() + g + g.transpose();
    }
    return f.transpose() * f;
  }
};

TEST_P(MaterialProperty, StressIsTwiceEnergyDerivative_SweepAndTaylor) {
  INCISE_SEEDED_RNG(rng, 401);
  const Material m = material();
  for (const auto& d : deformation_families(rng)) {
    SCOPED_TRACE(d.family);
    const Mat3 c = c_of(m, d.f);
    if (m.linear_geometry() && c.determinant() <= 0.0) continue;  // linearized C may be indefinite
    // Direction H = Fᵀ Ĥ F: a spatial strain increment pulled back, so C + tH = Fᵀ(I + tĤ)F
    // stays far from singular for |t| ≤ 0.1 even near inversion.
    const Mat3 h = pullback_direction(m, d.f, random_symmetric(rng));
    const double s = 0.1;
    const auto phi = [&](double t) { return m.energy_density(c + t * h); };
    const double dw = 0.5 * m.stress(c).cwiseProduct(h).sum();  // dW = ½ S:H (S = 2∂W/∂C)
    const auto r = check_directional_derivative(phi, dw, s, m.lame().mu * h.norm());
    EXPECT_LE(r.best_relative_error, incise::test::kFdTolerance) << r.report;
    EXPECT_GE(r.taylor_order, incise::test::kMinTaylorOrder) << r.report;
  }
}

TEST_P(MaterialProperty, StressDerivativeMatchesStress_SweepAndTaylor) {
  INCISE_SEEDED_RNG(rng, 402);
  const Material m = material();
  for (const auto& d : deformation_families(rng)) {
    SCOPED_TRACE(d.family);
    const Mat3 c = c_of(m, d.f);
    const Mat3 h = pullback_direction(m, d.f, random_symmetric(rng));
    const Mat3 w = random_matrix(rng, 1.0);  // random contraction weight
    const double s = 0.1;
    const auto phi = [&](double t) { return m.stress(c + t * h).cwiseProduct(w).sum(); };
    const double ds = m.stress_derivative(c, h).cwiseProduct(w).sum();
    // Unit: stress derivative magnitude; near inversion C⁻¹ terms scale like 1/λ_min(C)².
    const double unit = m.lame().mu * h.norm() / std::pow(std::min(1.0, min_eig_c(d.f)), 2);
    const double terms = (m.stress(c).norm() + m.lame().mu * c.norm()) * w.norm();
    const auto r = check_directional_derivative(phi, ds, s, unit, terms);
    EXPECT_LE(r.best_relative_error, incise::test::kFdTolerance) << r.report;
    EXPECT_GE(r.taylor_order, incise::test::kMinTaylorOrder) << r.report;
  }
}

TEST_P(MaterialProperty, TangentModuliReproduceStressDerivative) {
  INCISE_SEEDED_RNG(rng, 403);
  const Material m = material();
  for (const auto& d : deformation_families(rng)) {
    SCOPED_TRACE(d.family);
    const Mat3 c = c_of(m, d.f);
    const Mat3 h = random_symmetric(rng);
    const auto k = m.moduli(c);
    // The models see C through E = ½(C − I) (strain_from_c) and rebuild C = I + 2E, which is an
    // ulp of C away where C_ii ∉ [½, 2]; near inversion (κ(C) ≈ 1e6) that moves C⁻¹ by ~κ·ε, so
    // the expected value uses the C the model evaluates.
    const Mat3 c_model = Mat3::Identity() + 2.0 * (0.5 * (c - Mat3::Identity()));
    const Mat3 ci = c_model.inverse();
    const Mat3 expected = k.c1 * h.trace() * Mat3::Identity() + k.c2 * h +
                          k.c3 * ci.cwiseProduct(h).sum() * ci + k.c4 * ci * h * ci;
    const Mat3 got = m.stress_derivative(c, h);
    // Same formula evaluated in a different order: round-off relative to the largest term. The
    // models form C⁻¹ from E (neo-Hookean: I − C⁻¹ from the adjugate of E), the expectation by
    // inverting C: two evaluations of C⁻¹ agree to ~κ(C)·ε relative, so the bound grows with
    // κ(C) (1e6 in the near-inversion family) beyond the 1e-12 floor.
    const double scale =
        (std::abs(k.c1) + std::abs(k.c2) + (std::abs(k.c3) + std::abs(k.c4)) * ci.squaredNorm()) *
        h.norm();
    Eigen::SelfAdjointEigenSolver<Mat3> es(c_model);
    const double kappa = es.eigenvalues().maxCoeff() / es.eigenvalues().minCoeff();
    const double rel = std::max(1e-12, 64.0 * std::numeric_limits<double>::epsilon() * kappa);
    EXPECT_LE((got - expected).norm(), rel * scale) << "kappa(C) = " << kappa;
  }
}

TEST_P(MaterialProperty, StressIsSymmetricAndTangentHasMajorSymmetry) {
  INCISE_SEEDED_RNG(rng, 404);
  const Material m = material();
  for (const auto& d : deformation_families(rng)) {
    SCOPED_TRACE(d.family);
    const Mat3 c = c_of(m, d.f);
    const Mat3 s = m.stress(c);
    // Symmetry: S is built symmetric; exact up to round-off of the largest entry.
    EXPECT_LE((s - s.transpose()).norm(), 1e-14 * (1.0 + s.norm()));
    const Mat3 a = random_symmetric(rng);
    const Mat3 b = random_symmetric(rng);
    const double ab = a.cwiseProduct(m.stress_derivative(c, b)).sum();
    const double ba = b.cwiseProduct(m.stress_derivative(c, a)).sum();
    // A:(∂S/∂C:B) = B:(∂S/∂C:A) (hyperelastic); round-off of ~30 terms of the tangent's scale.
    const double scale =
        m.stress_derivative(c, a).norm() * b.norm() + m.stress_derivative(c, b).norm() * a.norm();
    EXPECT_LE(std::abs(ab - ba), 1e-12 * scale);
  }
}

TEST_P(MaterialProperty, ReferenceIsStressFreeWithZeroEnergy) {
  const Material m = material();
  const auto e = m.evaluate(Mat3::Identity());
  EXPECT_FALSE(e.inverted);
  // Exact: every model's W(I) and S(I) vanish identically; allow one ulp-level round-off.
  EXPECT_LE(std::abs(e.energy), 1e-15 * m.lame().mu);
  EXPECT_LE(e.second_piola.norm(), 1e-14 * m.lame().mu);
}

TEST_P(MaterialProperty, FrameIndifferenceAndIsotropy) {
  const Material m = material();
  INCISE_SEEDED_RNG(rng, 405);
  if (m.linear_geometry()) {
    // The linear model (linear geometry, (2.22)) is not frame-indifferent: a rigid rotation Q by
    // θ about n has ε = sym(Q) − I = (cos θ − 1)(I − nnᵀ), hence the known defect of §4.3.2
    // in closed form, W(Q) = 2(μ + λ)(1 − cos θ)² > 0 (growing like θ⁴).
    const double mu = m.lame().mu, lam = m.lame().lambda;
    std::normal_distribution<double> n01(0.0, 1.0);
    for (const double theta : {1e-2, 0.3, 1.0, 2.5}) {
      const Eigen::Vector3d axis = Eigen::Vector3d(n01(rng), n01(rng), n01(rng)).normalized();
      const Mat3 q = Eigen::AngleAxisd(theta, axis).toRotationMatrix();
      const double c = 1.0 - std::cos(theta);
      const double exact = 2.0 * (mu + lam) * c * c;
      // Round-off of ε's O(1) entries (cancellation in cos θ − 1): ~1e-16 (μ + λ) absolute in
      // ε, so 1e-15 (μ + λ) absolute plus 1e-13 relative in W.
      EXPECT_NEAR(m.evaluate(q).energy, exact, 1e-13 * exact + 1e-15 * (mu + lam)) << theta;
    }
    return;
  }
  for (const auto& d : deformation_families(rng)) {
    SCOPED_TRACE(d.family);
    const Mat3 q = random_rotation(rng);
    const double w = m.evaluate(d.f).energy;
    const double wqf = m.evaluate(q * d.f).energy;
    const double wfq = m.evaluate(d.f * q).energy;
    // W(QF) = W(F) (frame indifference) and W(FQ) = W(F) (isotropy); round-off of W's terms,
    // which near inversion include μ|ln J| ≈ 7μ.
    // det C = (det F)² is computed from O(1) entries, so its relative error grows like
    // 1/det F near inversion.
    const double scale = (std::abs(w) + m.lame().mu * (10.0 + d.f.squaredNorm())) *
                         (1.0 + 1.0 / std::abs(d.f.determinant()));
    EXPECT_LE(std::abs(wqf - w), 1e-13 * scale);
    EXPECT_LE(std::abs(wfq - w), 1e-13 * scale);
    if (d.family == "pure rotation") {
      EXPECT_LE(std::abs(w), 1e-13 * m.lame().mu);  // rigid rotations store no energy
    }
  }
}

/// λ of the linear model a model reduces to at small strain: λ for all but Veronda-Westmann,
/// whose form (§4.3.4) linearizes to λ_eff = λ + 2μ(2γ − 1).
double lambda_effective(const Material& m) {
  const auto& l = m.lame();
  if (m.name() == "veronda-westmann") return l.lambda + 2.0 * l.mu * (2.0 * l.gamma - 1.0);
  return l.lambda;
}

TEST_P(MaterialProperty, SmallStrainAgreesWithLinearElasticity) {
  INCISE_SEEDED_RNG(rng, 406);
  const Material m = material();
  const double lam = lambda_effective(m);
  const double mu = m.lame().mu;
  for (int trial = 0; trial < 4; ++trial) {
    const double eps = 1e-6;
    const Mat3 g = random_matrix(rng, eps);
    const Mat3 strain = 0.5 * (g + g.transpose());
    const Mat3 p_lin = 2.0 * mu * strain + lam * strain.trace() * Mat3::Identity();
    const Mat3 p = m.evaluate(Mat3::Identity() + g).first_piola;
    // Nonlinear terms are O(ε²) against O(ε) stresses: relative difference O(ε) = 1e-6; the
    // constants (stretch coefficients up to ~10) justify 1e-4.
    EXPECT_LE((p - p_lin).norm(), 1e-4 * p_lin.norm());
  }
}

TEST(VerondaWestmann, LinearizesToLambdaEffectiveNotLambda) {
  // §4.3.4: the small-strain limit of (4.7) has λ_eff = λ + 2μ(2γ − 1). Check both that it
  // matches λ_eff and that it does *not* match λ (for γ ≠ ½, where they differ).
  Parameters p = test_parameters();
  p.gamma = 1.5;
  const Material m("veronda-westmann", p);
  const double mu = m.lame().mu;
  const double lam_eff = m.lame().lambda + 2.0 * mu * (2.0 * p.gamma - 1.0);
  const double eps = 1e-7;
  const Mat3 f = Mat3::Identity() + eps * Mat3::Identity();  // pure dilation ε
  const double sigma = m.evaluate(f).first_piola(0, 0);
  const double expected_eff = (2.0 * mu + 3.0 * lam_eff) * eps;
  const double expected_lam = (2.0 * mu + 3.0 * m.lame().lambda) * eps;
  // O(ε) relative nonlinearity (ε = 1e-7, coefficients ~10): 1e-5.
  EXPECT_NEAR(sigma, expected_eff, 1e-5 * std::abs(expected_eff));
  EXPECT_GT(std::abs(sigma - expected_lam), 0.1 * std::abs(expected_lam));
}

/// Hand-derived first Piola-Kirchhoff stress and energy for F = diag(a, b, c) (P is diagonal,
/// P_11 given, others by cyclic permutation) and for simple shear F = I + k e1⊗e2 (P_12, W).
struct ClosedForm {
  std::function<double(double, double, double)> p11_diag;
  std::function<double(double)> p12_shear;
  std::function<double(double)> w_shear;
};

std::map<std::string, ClosedForm> closed_forms(const incise::material::Lame& l) {
  const double mu = l.mu, lam = l.lambda, g = l.gamma;
  std::map<std::string, ClosedForm> out;
  // Linear: ε = diag(a−1, b−1, c−1); P = 2με + λ tr ε I. Shear: ε12 = k/2, W = μk²/2.
  out["linear"] = {
      [=](double a, double b, double c) { return 2 * mu * (a - 1) + lam * (a + b + c - 3); },
      [=](double k) { return mu * k; }, [=](double k) { return 0.5 * mu * k * k; }};
  // StVK: P11 = a(μ(a² − 1) + λ/2 (a² + b² + c² − 3)); shear: P12 = μk + μk³ + λk³/2,
  // W = μk²/2 + μk⁴/4 + λk⁴/8.
  out["stvk"] = {[=](double a, double b, double c) {
                   return a * (mu * (a * a - 1) + 0.5 * lam * (a * a + b * b + c * c - 3));
                 },
                 [=](double k) { return mu * k + mu * k * k * k + 0.5 * lam * k * k * k; },
                 [=](double k) {
                   return 0.5 * mu * k * k + 0.25 * mu * std::pow(k, 4) + lam * std::pow(k, 4) / 8;
                 }};
  // Neo-Hookean: P = μ(F − F⁻ᵀ) + λJ(J − 1)F⁻ᵀ → P11 = μ(a − 1/a) + λJ(J − 1)/a, J = abc;
  // shear (J = 1): P12 = μk, W = μk²/2.
  out["neohookean"] = {[=](double a, double b, double c) {
                         const double j = a * b * c;
                         return mu * (a - 1 / a) + lam * j * (j - 1) / a;
                       },
                       [=](double k) { return mu * k; },
                       [=](double k) { return 0.5 * mu * k * k; }};
  // Veronda-Westmann: W(a,b,c) from §4.3.4 with ι1 = Σa², ι2 = Σa²b², ι3 = a²b²c² and
  // P11 = ∂W/∂a = 2μ a e − μ a (b² + c²) + λ/2 (a b² c² − 1/a), e = exp(γ(ι1 − 3)).
  // Shear: ι1 = ι2 = 3 + k², ι3 = 1: W = ½((2μ/γ)(e^{γk²} − 1) − μk²), P12 = μk(2e^{γk²} − 1).
  out["veronda-westmann"] = {
      [=](double a, double b, double c) {
        const double e = std::exp(g * (a * a + b * b + c * c - 3));
        return 2 * mu * a * e - mu * a * (b * b + c * c) + 0.5 * lam * (a * b * b * c * c - 1 / a);
      },
      [=](double k) { return mu * k * (2 * std::exp(g * k * k) - 1); },
      [=](double k) { return 0.5 * (2 * mu / g * (std::exp(g * k * k) - 1) - mu * k * k); }};
  return out;
}

TEST_P(MaterialProperty, ClosedFormHomogeneousStates) {
  const Material m = material();
  const auto forms = closed_forms(m.lame());
  const auto it = forms.find(m.name());
  ASSERT_NE(it, forms.end()) << "registered model '" << m.name()
                             << "' has no hand-derived closed form in this test: add one";
  const ClosedForm& cf = it->second;
  const double abc[][3] = {{1.3, 0.8, 1.1}, {2.0, 0.5, 0.7}, {0.6, 0.6, 0.6}, {3.0, 1.0, 1.0}};
  for (const auto& s : abc) {
    const Mat3 f = Eigen::Vector3d(s[0], s[1], s[2]).asDiagonal();
    const Mat3 p = m.evaluate(f).first_piola;
    const double ref[3] = {cf.p11_diag(s[0], s[1], s[2]), cf.p11_diag(s[1], s[2], s[0]),
                           cf.p11_diag(s[2], s[0], s[1])};
    // Same quantity by two formula routes: round-off relative to the stress scale.
    const double tol =
        1e-12 * (std::abs(ref[0]) + std::abs(ref[1]) + std::abs(ref[2]) + m.lame().mu);
    for (int i = 0; i < 3; ++i)
      EXPECT_NEAR(p(i, i), ref[i], tol) << "diag " << s[0] << " " << s[1] << " " << s[2];
    EXPECT_NEAR(p(0, 1), 0.0, tol);
    EXPECT_NEAR(p(1, 2), 0.0, tol);
  }
  for (double k : {0.1, 0.5, 1.5}) {
    Mat3 f = Mat3::Identity();
    f(0, 1) = k;
    const auto e = m.evaluate(f);
    const double tol = 1e-12 * (std::abs(cf.p12_shear(k)) + m.lame().mu);
    EXPECT_NEAR(e.first_piola(0, 1), cf.p12_shear(k), tol) << "shear " << k;
    EXPECT_NEAR(e.energy, cf.w_shear(k), 1e-12 * (std::abs(cf.w_shear(k)) + m.lame().mu))
        << "shear " << k;
  }
}

TEST_P(MaterialProperty, InvertedDeformationBehaviour) {
  const Material m = material();
  const Mat3 reflect = Eigen::Vector3d(1.0, 1.0, -1.0).asDiagonal();
  const Mat3 squash = Eigen::Vector3d(1.1, 0.9, -0.2).asDiagonal();
  if (m.linear_geometry()) {
    // Linear geometry has no notion of inversion: finite energy, defined stress.
    EXPECT_FALSE(m.evaluate(reflect).inverted);
    EXPECT_TRUE(std::isfinite(m.evaluate(reflect).energy));
  } else if (m.defined_when_inverted()) {
    // StVK: defined but unphysical. The reflected tet has C = I: stress-free, zero energy.
    const auto e = m.evaluate(reflect);
    EXPECT_FALSE(e.inverted);
    EXPECT_EQ(e.energy, 0.0);
    EXPECT_EQ(e.first_piola.norm(), 0.0);
    EXPECT_TRUE(std::isfinite(m.evaluate(squash).energy));
  } else {
    // Log models: det F ≤ 0 is reported inverted with W = +∞ (never NaN).
    for (const Mat3& f : {reflect, squash, Mat3(Mat3::Zero())}) {
      const auto e = m.evaluate(f);
      EXPECT_TRUE(e.inverted);
      EXPECT_TRUE(std::isinf(e.energy) && e.energy > 0);
      EXPECT_TRUE(e.first_piola.allFinite());
    }
    EXPECT_TRUE(std::isinf(m.energy_density(Mat3::Zero())));
  }
}

INSTANTIATE_TEST_SUITE_P(AllRegistered, MaterialProperty,
                         ::testing::ValuesIn(incise::material::registered_material_names()),
                         incise::test::material_param_name);

TEST(MaterialRegistry, NamesAndUnknownModel) {
  const auto names = incise::material::registered_material_names();
  const std::vector<std::string> expected = {"linear", "stvk", "neohookean", "veronda-westmann"};
  EXPECT_EQ(names, expected);
  try {
    Material m("mooney-rivlin", test_parameters());
    FAIL() << "unknown model accepted";
  } catch (const incise::ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("neohookean"), std::string::npos) << e.what();
  }
}

TEST(MaterialParameters, RejectsInadmissibleValuesNamingTheParameter) {
  struct Case {
    Parameters p;
    const char* name;
  };
  std::vector<Case> cases;
  const double nan = std::nan("");
  const double inf = std::numeric_limits<double>::infinity();
  auto with = [](auto f) {
    Parameters p = test_parameters();
    f(p);
    return p;
  };
  cases.push_back({with([](Parameters& p) { p.youngs_modulus = 0.0; }), "E (Young"});
  cases.push_back({with([](Parameters& p) { p.youngs_modulus = -1.0; }), "E (Young"});
  cases.push_back({with([&](Parameters& p) { p.youngs_modulus = inf; }), "E (Young"});
  cases.push_back({with([](Parameters& p) { p.poisson_ratio = 0.5; }), "nu (Poisson"});
  cases.push_back({with([](Parameters& p) { p.poisson_ratio = -1.0; }), "nu (Poisson"});
  cases.push_back({with([&](Parameters& p) { p.poisson_ratio = nan; }), "nu (Poisson"});
  cases.push_back({with([](Parameters& p) { p.gamma = -0.1; }), "gamma"});
  cases.push_back({with([&](Parameters& p) { p.gamma = nan; }), "gamma"});
  cases.push_back({with([](Parameters& p) { p.density = -1.0; }), "rho"});
  for (const auto& c : cases) {
    for (const auto& name : incise::material::registered_material_names()) {
      try {
        Material m(name, c.p);
        FAIL() << "accepted inadmissible parameters for " << name << " (" << c.name << ")";
      } catch (const incise::ParameterError& e) {
        EXPECT_NE(std::string(e.what()).find(c.name), std::string::npos) << e.what();
      }
    }
  }
  // Admissible extremes are accepted: ν close to 0.5 and negative ν, E over many decades.
  for (double nu : {-0.99, 0.0, 0.4999}) {
    Parameters p = test_parameters();
    p.poisson_ratio = nu;
    EXPECT_NO_THROW(Material("neohookean", p));
  }
  for (double e : {1e-3, 1e9}) {
    Parameters p = test_parameters();
    p.youngs_modulus = e;
    EXPECT_NO_THROW(Material("stvk", p));
  }
}

TEST(MaterialParameters, LameConstantsInvertEqs218And219) {
  Parameters p = test_parameters();
  p.youngs_modulus = 2.5e4;
  p.poisson_ratio = 0.42;
  const auto l = incise::material::to_lame(p);
  // (2.18): E = μ(3λ + 2μ)/(λ + μ); (2.19): ν = λ/(2(λ + μ)); exact up to a few ulps.
  EXPECT_NEAR(l.mu * (3 * l.lambda + 2 * l.mu) / (l.lambda + l.mu), p.youngs_modulus,
              1e-10 * p.youngs_modulus);
  EXPECT_NEAR(l.lambda / (2 * (l.lambda + l.mu)), p.poisson_ratio, 1e-14);
}

}  // namespace
