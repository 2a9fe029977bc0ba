// fem::element_fields (the VTU cell data of docs/mesh_formats.md "Fields"): on an affine
// displacement u = (F − I)X of a box every tetrahedron has the same F, so each element's strain,
// stresses and energy density must equal the closed-form values of F for each registered model —
// written here from the thesis formulas in C (§4.3: (2.17), (4.5)–(4.7)), not from the kernels'
// strain-based forms, so the test checks the one kinematics path against independent algebra.
// The plane-stress triangles (§6.3) are checked against the same closed forms at F = diag(F₂, q).

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

// The material `name` at the closed-form tests' parameters (E = 1e4 Pa, ν = 0.3, γ = 2).
material::Material test_material(const std::string& name) {
  material::Parameters par;
  par.youngs_modulus = 1e4;
  par.poisson_ratio = 0.3;
  par.gamma = 2.0;
  return material::Material(name, par);
}

// Element i of `got` equals `want`: strain and W within `rel_strain`, S, σ and von Mises within
// `rel_stress`, each relative to the largest component of its tensor (or |W|).
void expect_element_equals(const ElementFields& got, std::size_t i, const Expected& want,
                           double rel_strain, double rel_stress) {
  const auto e6 = voigt6(want.strain), s6 = voigt6(want.s), c6 = voigt6(want.sigma);
  const double se = want.strain.cwiseAbs().maxCoeff(), ss = want.s.cwiseAbs().maxCoeff(),
               sc = want.sigma.cwiseAbs().maxCoeff();
  EXPECT_EQ(got.inverted[i], 0) << "element " << i;
  for (int k = 0; k < 6; ++k) {
    EXPECT_NEAR(got.strain[6 * i + k], e6[k], rel_strain * se) << "element " << i << " comp " << k;
    EXPECT_NEAR(got.second_piola[6 * i + k], s6[k], rel_stress * ss) << "element " << i;
    EXPECT_NEAR(got.cauchy[6 * i + k], c6[k], rel_stress * sc) << "element " << i;
  }
  EXPECT_NEAR(got.von_mises[i], von_mises(want.sigma), rel_stress * sc) << "element " << i;
  EXPECT_NEAR(got.energy_density[i], want.w, rel_strain * std::abs(want.w)) << "element " << i;
}

// Every one of the `n` elements of `got` in uniaxial stress `sigma` along x: σxx = sigma,
// σyy = σzz = 0 and von Mises |sigma|, within 1e-10·|sigma| (ν a is not exact in binary and the
// lateral stresses cancel to ~1e-16·E).
void expect_uniaxial(const ElementFields& got, Index n, double sigma) {
  for (std::size_t i = 0; i < static_cast<std::size_t>(n); ++i) {
    EXPECT_NEAR(got.cauchy[6 * i], sigma, 1e-10 * std::abs(sigma)) << "element " << i;
    EXPECT_NEAR(got.cauchy[6 * i + 1], 0.0, 1e-10 * std::abs(sigma)) << "element " << i;
    EXPECT_NEAR(got.cauchy[6 * i + 2], 0.0, 1e-10 * std::abs(sigma)) << "element " << i;
    EXPECT_NEAR(got.von_mises[i], std::abs(sigma), 1e-10 * std::abs(sigma)) << "element " << i;
  }
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
    const material::Material mat = test_material(name);
    const ElasticProblem problem(m, mat);
    const ElementFields got = element_fields(problem, u);
    const Expected want = closed_form(name, mat.lame(), f);
    ASSERT_EQ(got.strain.size(), 6u * m.num_cells());
    for (Index e = 0; e < m.num_cells(); ++e)
      expect_element_equals(got, static_cast<std::size_t>(e), want, 1e-11, 1e-11);
  }
}

// Uniaxial stress σ = diag(σ, 0, 0) in the linear model: u = (a X, −ν a Y, −ν a Z) gives
// σxx = E a and zero lateral stress; von Mises = |σxx| for tension and compression.
// Tolerance: expect_uniaxial.
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
    SCOPED_TRACE("a = " + std::to_string(a));
    expect_uniaxial(got, m.num_cells(), 2e5 * a);
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

VecX affine_displacement_2d(const mesh::MeshData& m, const Mat2& f2) {
  VecX u(2 * m.num_points());
  for (Index i = 0; i < m.num_points(); ++i)
    u.segment<2>(2 * i) = (f2 - Mat2::Identity()) * m.points.col(i).head<2>();
  return u;
}

// Plane stress (§6.3), each model, an in-plane F₂ with stretch, compression and shear: every
// triangle's fields equal the 3D closed forms at F = diag(F₂, q), q = √(1 + 2E_zz) read from
// the output (linear model: q = 1 + ε_zz), and that state has S_zz = 0 — the closed form
// confirms the out-of-plane solve independently. Tolerances: S_zz ≤ 1e-8 of the stress scale
// is plane_stress.hpp's acceptance test; the other components 1e-10 relative (q carries the
// rounding of E_zz into the closed form's logarithms and exponential, ~10² ulps).
TEST(ElementFields, PlaneStressTrianglesEqualTheClosedFormAtDiagF2QWithZeroSzz) {
  const mesh::MeshData m = mesh::make_rectangle(3, 2, 0.3, 0.2, mesh::GridDiagonal::kAlternating);
  Mat2 f2;
  f2 << 1.1, 0.05, 0.02, 0.95;
  const VecX u = affine_displacement_2d(m, f2);
  for (const std::string& name : material::registered_material_names()) {
    SCOPED_TRACE(name);
    const material::Material mat = test_material(name);
    const PlaneStressProblem problem(m, mat, 0.01);
    const ElementFields got = element_fields(problem, u);
    ASSERT_EQ(got.strain.size(), 6u * m.num_cells());
    for (Index e = 0; e < m.num_cells(); ++e) {
      const std::size_t i = static_cast<std::size_t>(e);
      const double ezz = got.strain[6 * i + 2];
      Mat3 f = Mat3::Zero();
      f.topLeftCorner<2, 2>() = f2;
      f(2, 2) = name == "linear" ? 1.0 + ezz : std::sqrt(1.0 + 2.0 * ezz);
      const Expected want = closed_form(name, mat.lame(), f);
      EXPECT_LT(ezz, 0.0);  // the slab thins under the in-plane stretch
      EXPECT_NEAR(want.s(2, 2), 0.0, 1e-8 * want.s.cwiseAbs().maxCoeff()) << "element " << e;
      expect_element_equals(got, i, want, 1e-10, 1e-8);
    }
  }
}

// Uniaxial plane stress in the linear model: u = (a X, −ν a Y) gives σxx = E a, σyy = σxy = 0,
// the out-of-plane strain ε_zz = −ν a, and von Mises |σxx|. Tolerance as in the 3D test.
TEST(ElementFields, PlaneStressUniaxialVonMisesIsItsMagnitude) {
  const mesh::MeshData m = mesh::make_rectangle(2, 2, 0.1, 0.1);
  material::Parameters par;
  par.youngs_modulus = 3.4e4;
  par.poisson_ratio = 0.34;
  const PlaneStressProblem problem(m, material::Material("linear", par), 0.01);
  for (double a : {1e-3, -2e-3}) {
    const Mat2 f2 = Eigen::Vector2d(1 + a, 1 - 0.34 * a).asDiagonal();
    const ElementFields got = element_fields(problem, affine_displacement_2d(m, f2));
    SCOPED_TRACE("a = " + std::to_string(a));
    expect_uniaxial(got, m.num_cells(), 3.4e4 * a);
    for (Index e = 0; e < m.num_cells(); ++e) {
      const std::size_t i = static_cast<std::size_t>(e);
      EXPECT_NEAR(got.strain[6 * i + 2], -0.34 * a, 1e-10 * std::abs(a));
      // W = ½σ:ε = ½ E a²
      EXPECT_NEAR(got.energy_density[i], 0.5 * 3.4e4 * a * a, 1e-10 * 3.4e4 * a * a);
    }
  }
}

// A triangle turned inside out (det F₂ < 0) under a log model: flagged, its fields 0.
TEST(ElementFields, PlaneStressInvertedTriangleIsFlaggedWithZeroFields) {
  const mesh::MeshData m = mesh::make_rectangle(1, 1, 1.0, 1.0);
  const PlaneStressProblem problem(m, material::Material("neohookean", material::Parameters{}),
                                   0.01);
  const Mat2 f2 = Eigen::Vector2d(1.0, -0.5).asDiagonal();
  const ElementFields got = element_fields(problem, affine_displacement_2d(m, f2));
  for (Index e = 0; e < m.num_cells(); ++e) {
    EXPECT_EQ(got.inverted[static_cast<std::size_t>(e)], 1);
    EXPECT_EQ(got.energy_density[static_cast<std::size_t>(e)], 0.0);
    EXPECT_EQ(got.von_mises[static_cast<std::size_t>(e)], 0.0);
  }
}

}  // namespace
}  // namespace incise::fem
