#pragma once
/// \file material.hpp
/// Runtime material object and the registry of models by name ("linear", "stvk",
/// "neohookean", "veronda-westmann"; see models.hpp for the energies). The interface is the
/// thesis' (§4.3): W(C), S(C) = 2∂W/∂C and ∂S/∂C : H, plus a deformation-gradient level
/// evaluation that handles det F ≤ 0 explicitly. The C-level functions are as accurate as C
/// (E = ½(C − I) loses what C lost); evaluate(F) computes the strain from G = F − I like the
/// element kernels.
///
/// The material knows no mesh: it is tested on bare deformations.

#include <incise/core/types.hpp>
#include <incise/material/models.hpp>
#include <incise/material/parameters.hpp>

#include <string>
#include <vector>

namespace incise::material {

/// Names of all registered models, in ModelList order.
std::vector<std::string> registered_material_names();

/// Index in ModelList of the model called `name`; throws ParameterError listing the known
/// names when there is none.
int model_index(const std::string& name);

/// Outcome of evaluating a material at a deformation gradient F.
struct PointEvaluation {
  bool inverted = false;  ///< det F ≤ 0 and the model is undefined there (W = +∞, P = 0)
  double energy = 0.0;    ///< W(F) in J/m³ (+∞ when inverted)
  Mat3 first_piola;       ///< P = F·S (Pa); for the linear model P = S(ε) (linear geometry)
  Mat3 second_piola;      ///< S (Pa)
};

/// A registered model together with validated parameters.
class Material {
 public:
  /// Model `name` (see registered_material_names()) with parameters `p`. Throws
  /// ParameterError for an unknown name or inadmissible parameters (parameters.hpp).
  Material(const std::string& name, const Parameters& p);

  /// Registry name of the model.
  const std::string& name() const { return name_; }
  /// Index of the model in ModelList (for visit_model).
  int model_index() const { return index_; }
  /// Parameters as given.
  const Parameters& parameters() const { return parameters_; }
  /// Lamé constants (2.18)–(2.19) and γ.
  const Lame& lame() const { return lame_; }
  /// Density ρ (kg/m³).
  double density() const { return parameters_.density; }
  /// True for the linear model: C is the linearized I + G + Gᵀ and T = S (2.22).
  bool linear_geometry() const;
  /// False when det F ≤ 0 makes the energy undefined (log terms: neo-Hookean, VW).
  bool defined_when_inverted() const;

  /// W(C) in J/m³; +∞ when the model has a log term and det C ≤ 0.
  double energy_density(const Mat3& c) const;
  /// S(C) = 2∂W/∂C in Pa. Precondition for log models: det C > 0.
  Mat3 stress(const Mat3& c) const;
  /// ∂S/∂C : H in Pa, for symmetric H. Precondition as for stress().
  Mat3 stress_derivative(const Mat3& c, const Mat3& h) const;
  /// The coefficients c1..c4 of ∂S/∂C at C (models.hpp, TangentModuli).
  TangentModuli<double> moduli(const Mat3& c) const;

  /// Evaluates W and the stresses at deformation gradient F (for the linear model F = I + G
  /// and the strain is linearized). Inverted (det F ≤ 0 for log models) gives W = +∞.
  PointEvaluation evaluate(const Mat3& f) const;

 private:
  std::string name_;
  int index_ = 0;
  Parameters parameters_;
  Lame lame_;
};

}  // namespace incise::material
