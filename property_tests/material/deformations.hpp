#pragma once
/// \file deformations.hpp
/// Deformation-gradient families shared by the material and fem property tests (issue 3):
/// identity, small strain, random non-symmetric F with det F ∈ [0.2, 5], stretch 3, near
/// inversion (det F = 1e-3) and pure rotations.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <random>
#include <string>
#include <vector>

namespace incise::test {

using Mat3 = Eigen::Matrix3d;

inline Mat3 random_matrix(std::mt19937_64& rng, double scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Mat3 m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m(i, j) = scale * u(rng);
  return m;
}

inline Mat3 random_symmetric(std::mt19937_64& rng) {
  const Mat3 m = random_matrix(rng, 1.0);
  return 0.5 * (m + m.transpose());
}

inline Mat3 random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  return q.toRotationMatrix();
}

/// A named deformation gradient.
struct Deformation {
  std::string family;
  Mat3 f;
};

/// The deformation families of issue 3: identity, small strain, random non-symmetric F with
/// det F ∈ [0.2, 5], stretch 3, near inversion (det F = 1e-3), pure rotations.
inline std::vector<Deformation> deformation_families(std::mt19937_64& rng) {
  std::vector<Deformation> out;
  out.push_back({"identity", Mat3::Identity()});
  for (int i = 0; i < 2; ++i)
    out.push_back({"small strain", Mat3::Identity() + random_matrix(rng, 1e-4)});
  for (int i = 0; i < 4;) {
    const Mat3 f = Mat3::Identity() + random_matrix(rng, 0.6);
    const double d = f.determinant();
    if (d >= 0.2 && d <= 5.0) {
      out.push_back({"random det in [0.2,5]", f});
      ++i;
    }
  }
  out.push_back({"stretch 3", random_rotation(rng) * Eigen::Vector3d(3.0, 1.0, 1.0).asDiagonal() *
                                  random_rotation(rng)});
  {
    const Eigen::Vector3d s(1.2, 0.9, 1e-3 / (1.2 * 0.9));
    out.push_back(
        {"near inversion det 1e-3", random_rotation(rng) * s.asDiagonal() * random_rotation(rng)});
  }
  for (int i = 0; i < 2; ++i) out.push_back({"pure rotation", random_rotation(rng)});
  return out;
}

}  // namespace incise::test
