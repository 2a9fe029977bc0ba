#pragma once
/// \file material_parameters.hpp
/// The material parameters the element-level property tests share (fem: elastic problem,
/// stiffness, threads): one definition, so the suites test the same material.

#include <incise/material/parameters.hpp>

namespace incise::test {

/// E = 5 kPa, ν = 0.35, γ = 0.3 (Veronda–Westmann), ρ = 1100 kg/m³.
inline material::Parameters fem_test_parameters() {
  material::Parameters p;
  p.youngs_modulus = 5.0e3;
  p.poisson_ratio = 0.35;
  p.gamma = 0.3;
  p.density = 1.1e3;
  return p;
}

}  // namespace incise::test
