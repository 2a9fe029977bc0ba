// Certification checks on the element kernels and assembly (`incise certify`, catalogue in
// certify.cpp), for every registered material with the thesis' Table 4.1 parameters:
//   patch_test                affine displacements leave interior nodes force free (thesis §3.3
//                             deformation test), and the nodal forces are the consistent loads of
//                             Hooke's stress (2.20) on the boundary (computed here from E, ν)
//   matrix_free_vs_assembled  element-by-element K.d (4.4) equals the assembled sparse tangent
//                             (thesis §3.1; design.md §3 equivalences)
//   flop_table_4_3            flops per tetrahedron counted with incise::Counted against the
//                             thesis' hand counts, Table 4.3 (§4.3)

#include <incise/core/error.hpp>
#include <incise/fem/elastic_problem.hpp>
#include <incise/fixtures/deformations.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/mesh/tet_faces.hpp>
#include <incise/scene/scene_builder.hpp>

#include <algorithm>
#include <random>

#include "certify_checks.hpp"

namespace incise::certify::detail {

namespace {

/// Hooke's stress σ = λ tr(ε) I + 2μ ε of the small strain ε = (A + Aᵀ)/2 (Pa), thesis (2.20).
Mat3 hooke_stress(const Mat3& a, double lambda, double mu) {
  const Mat3 eps = 0.5 * (a + a.transpose());
  return lambda * eps.trace() * Mat3::Identity() + 2.0 * mu * eps;
}

/// The consistent nodal loads (N) of the constant stress σ on the boundary of `m`: each boundary
/// triangle of outward area vector n·A adds σ·n·A/3 to each of its vertices. For u = A x these
/// are the internal forces of a mesh whose stress is σ (divergence theorem, element by element).
VecX boundary_loads(const mesh::MeshData& m, const Mat3& sigma) {
  VecX f = VecX::Zero(3 * m.num_points());
  const mesh::CellMatrix faces = mesh::boundary_faces(m);
  for (Index k = 0; k < faces.cols(); ++k) {
    const Vec3 a = m.points.col(faces(0, k)), b = m.points.col(faces(1, k)),
               c = m.points.col(faces(2, k));
    const Vec3 area_normal = 0.5 * (b - a).cross(c - a);
    for (int v = 0; v < 3; ++v) f.segment<3>(3 * faces(v, k)) += sigma * area_normal / 3.0;
  }
  return f;
}

}  // namespace

Measurement measure_patch_test(const CertifyContext& /*ctx*/) {
  Measurement r;
  ReportTable t{
      "Affine displacements u = A x on a 3x3x3 unit box (six split)",
      {"material", "|A_ij| <= (interior test)", "max interior |g| / max |g|",
       "|A_ij| <= (Hooke test)", "||g - Hooke loads|| / ||Hooke loads||", "Hooke's lambda (Pa)"},
      {}};
  fixtures::Rng rng(20031107);
  const auto m = mesh::make_box(3, 3, 3, 1, 1, 1, mesh::CubeSplit::kSix);
  const double kLarge = 0.05, kSmall = 1e-5;
  for (const auto& name : material::registered_material_names()) {
    const scene::MaterialSpec spec = table_4_1_material(name);
    fem::ElasticProblem p(m, scene::make_material(spec));
    // Interior nodes force free at a finite deformation (any model: constant P).
    const Mat3 a = fixtures::random_matrix(rng, kLarge);
    VecX u(p.size());
    for (Index i = 0; i < m.num_points(); ++i) u.segment<3>(3 * i) = a * m.points.col(i);
    VecX g;
    if (p.gradient(u, g) != EvalStatus::kOk) throw Error("gradient failed for " + name);
    double gi = 0, gmax = 0;
    for (Index i = 0; i < m.num_points(); ++i) {
      const Vec3 x = m.points.col(i);
      const double f = g.segment<3>(3 * i).norm();
      gmax = std::max(gmax, f);
      const bool interior = (x.array() > 1e-9).all() && (x.array() < 1 - 1e-9).all();
      if (interior) gi = std::max(gi, f);
    }
    r.comparisons.push_back({name + ": max interior |g| / max |g|", "interior_force", gi / gmax});
    // Nodal forces against Hooke's law from E and nu (not from the material module's Lamé
    // constants): exactly for the linear model, in the small-strain limit for the others.
    const bool linear = name == "linear";
    const Mat3 b = linear ? a : fixtures::random_matrix(rng, kSmall);
    for (Index i = 0; i < m.num_points(); ++i) u.segment<3>(3 * i) = b * m.points.col(i);
    if (p.gradient(u, g) != EvalStatus::kOk) throw Error("gradient failed for " + name);
    const double e = spec.parameters.youngs_modulus, nu = spec.parameters.poisson_ratio;
    const double mu = e / (2 * (1 + nu));
    double lambda = e * nu / ((1 + nu) * (1 - 2 * nu));
    // Veronda-Westmann's small-strain limit has lambda + 2 mu (2 gamma - 1) (models.hpp, the
    // inconsistency thesis §4.3.4 remarks on).
    if (name == "veronda-westmann") lambda += 2 * mu * (2 * spec.parameters.gamma - 1);
    const VecX expected = boundary_loads(m, hooke_stress(b, lambda, mu));
    const double hooke = (g - expected).norm() / expected.norm();
    r.comparisons.push_back({name + ": ||g - Hooke loads|| / ||Hooke loads||",
                             linear ? "hooke_linear" : "hooke_small_strain", hooke});
    t.rows.push_back({name, fmt(kLarge), fmt(gi / gmax), fmt(linear ? kLarge : kSmall), fmt(hooke),
                      fmt(lambda)});
  }
  r.detail =
      "Constant stress is divergence free: interior nodes of an affinely deformed mesh carry no "
      "net internal force, and every nodal force is the consistent load of the stress on the "
      "boundary triangles (sigma n A / 3 per vertex). Hooke's sigma = lambda tr(eps) I + 2 mu eps "
      "is computed here from E = 1e4 Pa, nu = 0.3 (Table 4.1); random A (seed 20031107).";
  r.tables.push_back(t);
  return r;
}

Measurement measure_matrix_free(const CertifyContext& /*ctx*/) {
  Measurement r;
  ReportTable t{
      "The §4.2 cylinder, 3 rings, 7 layers (1134 tets, not a multiple of 4: the "
      "kernels' scalar tail runs too), random u and d",
      {"material", "relative difference"},
      {}};
  std::mt19937_64 rng(42);
  std::normal_distribution<double> nd(0.0, 1.0);
  const auto m = mesh::make_cylinder(0.1, 0.03, 3, 7);
  for (const auto& name : material::registered_material_names()) {
    fem::ElasticProblem p(m, scene::make_material(table_4_1_material(name)));
    VecX u(p.size()), d(p.size());
    for (Eigen::Index i = 0; i < u.size(); ++i) u[i] = 1e-4 * nd(rng), d[i] = nd(rng);
    VecX kd;
    if (p.hessian_product(u, d, kd) != EvalStatus::kOk) throw Error("K.d failed for " + name);
    if (p.assemble_tangent(u, fem::FixedDofTreatment::kKeep) != EvalStatus::kOk)
      throw Error("assembly failed for " + name);
    const VecX ka = p.tangent_matrix() * d;
    const double rel = (kd - ka).norm() / ka.norm();
    r.comparisons.push_back({name + ": ||K_mf d - K_asm d|| / ||K_asm d||", "relative", rel});
    t.rows.push_back({name, fmt(rel)});
  }
  r.detail = "Element-by-element products (4.4) against the assembled sparse tangent.";
  r.tables.push_back(t);
  return r;
}

Measurement measure_flop_table(const CertifyContext& /*ctx*/) {
  Measurement r;
  struct Row {
    const char* name;
    double force, derivative;
  };
  // Published reference values, thesis Table 4.3 ("Force", "Derivative" flops per tetrahedron).
  const Row thesis[] = {{"linear", 129, 129},
                        {"stvk", 235, 421},
                        {"neohookean", 277, 595},
                        {"veronda-westmann", 347, 797}};
  ReportTable t{"Flops per tetrahedron: counted with the counting scalar vs thesis Table 4.3",
                {"material", "force (ours)", "force (thesis)", "K.d (ours)", "derivative (thesis)",
                 "fused force + K.d (ours)"},
                {}};
  Series ours{"counted K.d", {}, {}, {}, false}, ref{"thesis Table 4.3", {}, {}, {}, true};
  int k = 0;
  for (const Row& row : thesis) {
    const fem::ElementFlops f =
        fem::element_flops(scene::make_material(table_4_1_material(row.name)));
    const double a = static_cast<double>(f.force);
    const double c = static_cast<double>(f.product);
    r.comparisons.push_back(
        {std::string(row.name) + ": Force, ours / thesis", "ratio", a / row.force});
    r.comparisons.push_back({std::string(row.name) + ": Derivative (our K_e.d), ours / thesis",
                             "ratio", c / row.derivative});
    t.rows.push_back({row.name, std::to_string(f.force), fmt(row.force), std::to_string(f.product),
                      fmt(row.derivative), std::to_string(f.force_and_product)});
    ours.x.push_back(k), ours.y.push_back(c);
    ref.x.push_back(k), ref.y.push_back(row.derivative);
    ++k;
  }
  r.detail =
      "Our kernels are counted by instantiating them with incise::Counted (exp charged 50 "
      "flops as in §4.2); the thesis counted the same formulas by hand (differences: "
      "verification/papers/nienhuys2003_table4_3/README.md). Force is compared with Force, our "
      "element product K_e.d (4.4) with the thesis' Derivative column.";
  r.tables.push_back(t);
  PlotOptions po;
  po.title = "Flops per tetrahedron: derivative K_e.d (4.4)";
  po.y_label = "flops";
  po.x_label = "material";
  po.x_categories = {"linear", "stvk", "neohookean", "veronda-westmann"};
  r.plots.push_back(ReportPlot{po, {ours, ref}});
  return r;
}

}  // namespace incise::certify::detail
