// fem::element_fields (the VTU cell data of docs/mesh_formats.md "Fields"): on an affine
// displacement u = (F − I)X of a box every tetrahedron has the same F, so each element's strain,
// stresses and energy density must equal the closed-form values of F for each registered model —
// written here from the thesis formulas in C (§4.3: (2.17), (4.5)–(4.7)), not from the kernels'
// strain-based forms, so the test checks the one kinematics path against independent algebra.

#include <incise/fem/element_fields.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/generators.hpp>

#include <gtest/gtest.h>

#include <cmath>

namespace incise::fem {
namespace {

struct Expected {
  Mat3 strain, s, sigma;
  double w;
};

// Closed forms of each model at F, from C = FᵀF (models.hpp's headline formulas).
Expected closed_form(const std::string& model, const material::Lame& p, const Mat3& f) {
  const Mat3 I = Mat3::Identity();
  Expected x;
  if (model == "linear") {
    x.strain = 0.5 * ((f - I) + (f - I).transpose());
    x.s = p.lambda * x.strain.trace() * I + 2 * p.mu * x.strain;
    x.sigma = x.s;
    x.w = 0.5 * p.lambda * std::pow(x.strain.trace(), 2) + p.mu * (x.strain.array().square()).sum();
    return x;
  }
  const Mat3 c = f.transpose() * f, ci = c.inverse();
  const double j = f.determinant(), i1 = c.trace(), i3 = c.determinant();
  const double i2 = 0.5 * (i1 * i1 - (c * c).trace());
  x.strain = 0.5 * (c - I);
  if (model == "stvk") {
    x.s = p.lambda * x.strain.trace() * I + 2 * p.mu * x.strain;
    x.w = 0.5 * p.lambda * std::pow(x.strain.trace(), 2) + p.mu * (x.strain.array().square()).sum();
  } else if (model == "neohookean") {
    x.s = p.mu * I + (p.lambda * (j - 1) * j - p.mu) * ci;
    x.w = 0.5 * p.mu * (i1 - 3) - p.mu * std::log(j) + 0.5 * p.lambda * (j - 1) * (j - 1);
  } else {  // veronda-westmann (4.7)
    const double e = std::exp(p.gamma * (i1 - 3));
    x.s = (2 * p.mu * e - p.mu * i1) * I + p.mu * c + 0.5 * p.lambda * (i3 - 1) * ci;
    x.w = 0.5 * ((2 * p.mu / p.gamma) * (e - 1) - p.mu * (i2 - 3) +
                 0.5 * p.lambda * (i3 - 1 - std::log(i3)));
  }
  x.sigma = f * x.s * f.transpose() / j;
  return x;
}

VecX affine_displacement(const mesh::MeshData& m, const Mat3& f) {
  VecX u(3 * m.num_points());
  for (Index i = 0; i < m.num_points(); ++i)
    u.segment<3>(3 * i) = (f - Mat3::Identity()) * m.points.col(i);
  return u;
}

// Each of the 4 models, a general F (stretch, compression and shear, det F ≈ 1.09). Tolerance
// 1e-11 relative to the largest component: both sides are O(1) formulas in doubles at a strain
// of 0.1 (no cancellation); G = U·Z⁻¹ of the box's 0.25 m cells carries a few ulps, and the
// exponential and logarithms of VW and neo-Hookean amplify them by at most ~10².
TEST(ElementFields, AffineDeformationGivesTheClosedFormInEveryElementForEveryModel) {
  const mesh::MeshData m = mesh::make_box(2, 2, 2, 0.5, 0.5, 0.5, mesh::CubeSplit::kSix);
  Mat3 f;
  f << 1.1, 0.05, 0.0, 0.02, 0.95, 0.03, 0.0, 0.01, 1.05;
  const VecX u = affine_displacement(m, f);
  for (const std::string& name : material::registered_material_names()) {
    SCOPED_TRACE(name);
    material::Parameters par;
    par.youngs_modulus = 1e4;
    par.poisson_ratio = 0.3;
    par.gamma = 2.0;
    const material::Material mat(name, par);
    const ElasticProblem problem(m, mat);
    const ElementFields got = element_fields(problem, u);
    const Expected want = closed_form(name, mat.lame(), f);
    const auto e6 = voigt6(want.strain), s6 = voigt6(want.s), c6 = voigt6(want.sigma);
    const double se = want.strain.cwiseAbs().maxCoeff(), ss = want.s.cwiseAbs().maxCoeff(),
                 sc = want.sigma.cwiseAbs().maxCoeff();
    ASSERT_EQ(got.strain.size(), 6u * m.num_cells());
    for (Index e = 0; e < m.num_cells(); ++e) {
      const std::size_t i = static_cast<std::size_t>(e);
      EXPECT_EQ(got.inverted[i], 0);
      for (int k = 0; k < 6; ++k) {
        EXPECT_NEAR(got.strain[6 * i + k], e6[k], 1e-11 * se) << "element " << e << " comp " << k;
        EXPECT_NEAR(got.second_piola[6 * i + k], s6[k], 1e-11 * ss) << "element " << e;
        EXPECT_NEAR(got.cauchy[6 * i + k], c6[k], 1e-11 * sc) << "element " << e;
      }
      EXPECT_NEAR(got.von_mises[i], von_mises(want.sigma), 1e-11 * sc);
      EXPECT_NEAR(got.energy_density[i], want.w, 1e-11 * std::abs(want.w));
    }
  }
}

// Uniaxial stress σ = diag(σ, 0, 0) in the linear model: u = (a X, −ν a Y, −ν a Z) gives
// σxx = E a and zero lateral stress; von Mises = |σxx| for tension and compression.
// Tolerance 1e-10·|σ|: ν a is not exact in binary and the lateral stresses cancel to ~1e-16·E.
TEST(ElementFields, VonMisesOfUniaxialStressIsItsMagnitude) {
  const mesh::MeshData m = mesh::make_box(2, 1, 1, 1.0, 0.5, 0.5, mesh::CubeSplit::kSix);
  material::Parameters par;
  par.youngs_modulus = 2e5;
  par.poisson_ratio = 0.3;
  const material::Material mat("linear", par);
  const ElasticProblem problem(m, mat);
  for (double a : {1e-3, -2e-3}) {
    const Mat3 f = Vec3(1 + a, 1 - 0.3 * a, 1 - 0.3 * a).asDiagonal();
    const ElementFields got = element_fields(problem, affine_displacement(m, f));
    const double sigma = 2e5 * a;
    for (Index e = 0; e < m.num_cells(); ++e) {
      const std::size_t i = static_cast<std::size_t>(e);
      EXPECT_NEAR(got.cauchy[6 * i], sigma, 1e-10 * std::abs(sigma));
      EXPECT_NEAR(got.cauchy[6 * i + 1], 0.0, 1e-10 * std::abs(sigma));
      EXPECT_NEAR(got.von_mises[i], std::abs(sigma), 1e-10 * std::abs(sigma)) << "a = " << a;
    }
  }
  // Pure shear τ: von Mises √3·τ.
  Mat3 shear = Mat3::Zero();
  shear(0, 1) = shear(1, 0) = 5.0;
  EXPECT_DOUBLE_EQ(von_mises(shear), std::sqrt(3.0) * 5.0);
}

// An inverted element of a log model: flagged, its fields 0 (never NaN or ∞).
TEST(ElementFields, InvertedElementIsFlaggedWithZeroFields) {
  const mesh::MeshData m = mesh::make_box(1, 1, 1, 1.0, 1.0, 1.0, mesh::CubeSplit::kSix);
  const material::Material mat("neohookean", material::Parameters{});
  const ElasticProblem problem(m, mat);
  const Mat3 f = Vec3(1.0, 1.0, -0.5).asDiagonal();  // reflection: det F < 0 everywhere
  const ElementFields got = element_fields(problem, affine_displacement(m, f));
  for (Index e = 0; e < m.num_cells(); ++e) {
    EXPECT_EQ(got.inverted[static_cast<std::size_t>(e)], 1);
    EXPECT_EQ(got.energy_density[static_cast<std::size_t>(e)], 0.0);
    EXPECT_EQ(got.von_mises[static_cast<std::size_t>(e)], 0.0);
  }
}

}  // namespace
}  // namespace incise::fem
