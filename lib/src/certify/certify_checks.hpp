#pragma once
// The measurements behind `incise certify` (private to the certify module).
//
// The public side is lib/include/incise/certify/certify.hpp: certify.cpp holds the check table
// (certify_catalogue) and run_certify, which judges each comparison a measurement returns against
// its band [min, max] in reference_data/certify/tolerances.json; certify_report.cpp renders the
// HTML page and the JSON summary. The measurements themselves are grouped by area, one file each:
//
//   certify_mesh.cpp         generators, the liver mesh's invariants (7.1)-(7.5), shipped scenes
//   certify_fem.cpp          patch test, matrix-free K.d, flops per element (thesis Table 4.3)
//   certify_solvers.cpp      cantilever (Table 3.1), CG == CHOLMOD, nonlinear CG / SS22 == Newton,
//                            augmented interactive cut == cut first (Yeung et al. 2016)
//   certify_performance.cpp  cost per iteration against thesis Table 4.5, rate as a fraction of
//                            the vector-add baseline measured interleaved in the same process
//
// A measurement returns its comparisons (quantity, band name, value) and the evidence (tables,
// plots); it never judges itself.

#include <incise/certify/certify.hpp>
#include <incise/certify/svg_plot.hpp>
#include <incise/scene/scene_builder.hpp>
#include <incise/scene/scene_spec.hpp>

#include <string>

namespace incise::certify::detail {

/// Numbers in report tables and details: format_number (svg_plot.hpp).
inline std::string fmt(double v) {
  return format_number(v);
}

/// The thesis' material parameters for `model` (Table 4.1: E = 1e4 Pa, ν = 0.3, ρ = 1000
/// kg/m³; γ = 8 for "veronda-westmann", 0 otherwise), as a scene MaterialSpec to build with
/// make_material (scene_builder.hpp).
inline scene::MaterialSpec table_4_1_material(const std::string& model) {
  scene::MaterialSpec m;
  m.model = model;
  m.parameters.youngs_modulus = 1e4;
  m.parameters.poisson_ratio = 0.3;
  m.parameters.gamma = model == "veronda-westmann" ? 8.0 : 0.0;
  m.parameters.density = 1000;
  return m;
}

/// ‖P ∇Π(u)‖ / ‖f_ext‖ of scene `b`'s (final) problem at `u`, recomputed from the forces — the
/// residual a solver's stopping rule is about, independent of what the solver reports; NaN when
/// the forces cannot be evaluated (inverted element). Defined in certify_solvers.cpp.
double recomputed_relative_residual(scene::BuiltScene& b, const VecX& u);

// certify_mesh.cpp
Measurement measure_box_volume(const CertifyContext& ctx);
Measurement measure_cylinder_volume(const CertifyContext& ctx);
Measurement measure_liver_validate(const CertifyContext& ctx);
Measurement measure_shipped_scenes(const CertifyContext& ctx);

// certify_fem.cpp
Measurement measure_patch_test(const CertifyContext& ctx);
Measurement measure_matrix_free(const CertifyContext& ctx);
Measurement measure_flop_table(const CertifyContext& ctx);

// certify_solvers.cpp
Measurement measure_cantilever(const CertifyContext& ctx);
Measurement measure_cg_vs_cholmod(const CertifyContext& ctx);
Measurement measure_solver_trade(const CertifyContext& ctx);
Measurement measure_augmented_cut(const CertifyContext& ctx);

// certify_performance.cpp
Measurement measure_table_4_5(const CertifyContext& ctx);

}  // namespace incise::certify::detail
