#pragma once
/// \file needle_support.hpp
/// What the needle property tests (2D and 3D problems and insertions) share: one definition.

#include <incise/core/types.hpp>
#include <incise/material/material.hpp>

#include <random>
#include <string>

namespace incise::test {

/// The thesis' needle material (§6.8.1): E = 3.4e4 Pa, ν = 0.34 unless given.
inline material::Material needle_material(const std::string& name = "linear", double nu = 0.34) {
  material::Parameters p;
  p.youngs_modulus = 3.4e4;
  p.poisson_ratio = nu;
  return material::Material(name, p);
}

/// n independent normal samples of standard deviation `scale`.
inline VecX gaussian_vector(std::mt19937_64& rng, Eigen::Index n, double scale) {
  std::normal_distribution<double> g(0.0, scale);
  VecX v(n);
  for (Eigen::Index i = 0; i < n; ++i) v[i] = g(rng);
  return v;
}

}  // namespace incise::test
