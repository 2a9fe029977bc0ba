#pragma once
/// \file parameters.hpp
/// Material parameters in engineering units and their conversion to Lamé constants (thesis
/// §2.1, eqs. (2.18)–(2.19)).

namespace incise::material {

/// Engineering parameters of an isotropic hyperelastic material (SI units).
struct Parameters {
  double youngs_modulus = 1.0e4;  ///< E in Pa; must be finite and > 0
  double poisson_ratio = 0.3;     ///< ν, dimensionless; must satisfy −1 < ν < 0.5
  double gamma = 0.0;             ///< Veronda-Westmann nonlinearity γ (dimensionless), ≥ 0
  double density = 1000.0;        ///< ρ in kg/m³; finite and ≥ 0
};

/// Lamé constants and the Veronda-Westmann γ, the form in which the kernels take parameters.
struct Lame {
  double lambda = 0.0;  ///< first Lamé constant λ (Pa)
  double mu = 0.0;      ///< shear modulus μ (Pa)
  double gamma = 0.0;   ///< Veronda-Westmann γ (dimensionless)
};

/// Validates `p` and converts it: μ = E / (2(1+ν)), λ = Eν / ((1+ν)(1−2ν)), the inverse of
/// (2.18)–(2.19). Throws ParameterError naming the offending parameter and its value when
/// E ≤ 0, ν ≤ −1, ν ≥ 0.5, γ < 0, ρ < 0 or any value is not finite.
Lame to_lame(const Parameters& p);

/// Throws ParameterError (see to_lame) when `p` is inadmissible; returns normally otherwise.
void validate(const Parameters& p);

}  // namespace incise::material
