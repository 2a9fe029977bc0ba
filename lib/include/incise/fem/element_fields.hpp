#pragma once
/// \file element_fields.hpp
/// Per-tetrahedron strain and stress of a displacement, for output (VTU cell data,
/// docs/mesh_formats.md "Fields"): computed by the element kernels' own kinematics
/// (TetKernel::kinematics: G = U·Z⁻¹, the strain from G, S from the material), so there is
/// one definition of each quantity. Symmetric tensors are stored as 6 components in ParaView's
/// order xx, yy, zz, xy, yz, xz (tensor components, not engineering shears).

#include <incise/fem/elastic_problem.hpp>

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

}  // namespace incise::fem
