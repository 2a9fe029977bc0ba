#pragma once
/// \file element_fields.hpp
/// Per-element strain and stress of a displacement, for output (VTU cell data,
/// docs/mesh_formats.md "Fields"), of tetrahedra and of plane-stress triangles (§6.3): computed
/// by the element kernels' own kinematics (TetKernel::kinematics, TriKernel::kinematics: G =
/// U·Z⁻¹, the strain from G, S from the material), and turned into the stored fields in one
/// place for both, so there is one definition of each quantity. Symmetric tensors are stored as
/// 6 components in ParaView's order xx, yy, zz, xy, yz, xz (tensor components, not engineering
/// shears).

#include <incise/fem/elastic_problem.hpp>
#include <incise/fem/plane_stress_problem.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace incise::fem {

/// The fields of every element of a problem, in mesh order.
struct ElementFields {
  /// Green–Lagrange strain E = ½(FᵀF − I) (dimensionless); for the linear model (linear
  /// geometry, thesis (2.22)) the infinitesimal strain ε = ½(G + Gᵀ).
  std::vector<double> strain;
  /// Second Piola–Kirchhoff stress S = ∂W/∂E (Pa); for the linear model S = σ = λ tr(ε) I + 2µ ε.
  std::vector<double> second_piola;
  /// Cauchy stress σ = J⁻¹ F S Fᵀ (Pa, J = det F); for the linear model σ = S.
  std::vector<double> cauchy;
  /// von Mises stress of σ: √(½[(σxx−σyy)² + (σyy−σzz)² + (σzz−σxx)²] + 3(σxy² + σyz² + σxz²))
  /// (Pa).
  std::vector<double> von_mises;
  /// Strain energy density W (J/m³, per reference volume).
  std::vector<double> energy_density;
  /// 1 where det F ≤ 0, 0 elsewhere. There the log models (neo-Hookean, Veronda–Westmann)
  /// are undefined and every field of the element is 0; StVK keeps E, S and W, σ and von
  /// Mises are 0.
  std::vector<std::uint8_t> inverted;
};

/// The six stored components (xx, yy, zz, xy, yz, xz) of a symmetric tensor.
std::array<double, 6> voigt6(const Mat3& t);

/// von Mises equivalent stress of a (symmetric) Cauchy stress σ (Pa).
double von_mises(const Mat3& sigma);

/// ElementFields of `problem` at displacement `u` (3 per node, m). Throws UsageError for a
/// wrong size.
ElementFields element_fields(const ElasticProblem& problem, const VecX& u);

/// ElementFields of a plane-stress slab at in-plane displacement `u` (2 per node, m), from the
/// 3D state diag(E₂, E₃₃) of material/plane_stress.hpp: in-plane components xx, yy, xy; zz of
/// the strain is the out-of-plane E₃₃ (the thickness change), S_zz and σ_zz are the solved
/// S₃₃ ≈ 0 (|S₃₃| ≤ 1e-8 of the stress scale, plane_stress.hpp), yz = xz = 0; F = diag(F₂, q),
/// q = √(1 + 2E₃₃), J = det F₂·q; von Mises of that σ (σ_zz = 0 to that accuracy:
/// √(σxx² − σxxσyy + σyy² + 3σxy²)); W per reference volume. "inverted" as for tetrahedra (det
/// F₂ ≤ 0 or q² ≤ 0). An element whose out-of-plane solve does not converge has NaN fields
/// (kNotConverged: no state exists) and inverted = 0. Throws UsageError for a wrong size.
ElementFields element_fields(const PlaneStressProblem& problem, const VecX& u);

}  // namespace incise::fem
