#include <incise/core/error.hpp>
#include <incise/fem/element_fields.hpp>
#include <incise/fem/tet_kernels.hpp>

#include <cmath>

namespace incise::fem {

std::array<double, 6> voigt6(const Mat3& t) {
  return {t(0, 0), t(1, 1), t(2, 2), t(0, 1), t(1, 2), t(0, 2)};
}

double von_mises(const Mat3& s) {
  const double a = s(0, 0) - s(1, 1), b = s(1, 1) - s(2, 2), c = s(2, 2) - s(0, 0);
  return std::sqrt(0.5 * (a * a + b * b + c * c) +
                   3.0 * (s(0, 1) * s(0, 1) + s(1, 2) * s(1, 2) + s(0, 2) * s(0, 2)));
}

ElementFields element_fields(const ElasticProblem& problem, const VecX& u) {
  INCISE_CHECK(u.size() == problem.size(), "element_fields: u has the wrong size");
  const Index ne = problem.num_elements();
  const std::size_t n = static_cast<std::size_t>(ne);
  ElementFields out;
  out.strain.assign(6 * n, 0.0);
  out.second_piola.assign(6 * n, 0.0);
  out.cauchy.assign(6 * n, 0.0);
  out.von_mises.assign(n, 0.0);
  out.energy_density.assign(n, 0.0);
  out.inverted.assign(n, 0);
  const material::Material& mat = problem.material();
  const material::Lame& lame = mat.lame();
  material::visit_model(mat.model_index(), [&](auto model) {
    using M = decltype(model);
    using K = TetKernel<M, double>;
    for (Index e = 0; e < ne; ++e) {
      Mat34T<double> x;
      for (int a = 0; a < 4; ++a) x.col(a) = u.segment<3>(3 * problem.cells()(a, e));
      typename K::State st;
      const std::size_t i = static_cast<std::size_t>(e);
      if (!K::kinematics(lame, problem.reference(e).z_inv, x, st)) {
        out.inverted[i] = 1;
        continue;
      }
      Mat3 sigma = st.s;
      if constexpr (!M::kLinearGeometry) {
        const double j = M::kUsesJ ? 1.0 + st.strain.jm1 : st.f.determinant();
        if (j > 0.0) {
          sigma = st.f * st.s * st.f.transpose() / j;
        } else {  // StVK past inversion: E, S and W exist, σ does not
          out.inverted[i] = 1;
          sigma.setZero();
        }
      }
      const auto e6 = voigt6(st.strain.e), s6 = voigt6(st.s), c6 = voigt6(sigma);
      for (int c = 0; c < 6; ++c) {
        out.strain[6 * i + c] = e6[c];
        out.second_piola[6 * i + c] = s6[c];
        out.cauchy[6 * i + c] = c6[c];
      }
      out.von_mises[i] = von_mises(sigma);
      out.energy_density[i] = M::energy(lame, st.strain);
    }
  });
  return out;
}

}  // namespace incise::fem
