#include <incise/core/error.hpp>
#include <incise/fem/element_fields.hpp>
#include <incise/fem/tet_kernels.hpp>
#include <incise/fem/tri_kernels.hpp>

#include <cmath>
#include <limits>

namespace incise::fem {

std::array<double, 6> voigt6(const Mat3& t) {
  return {t(0, 0), t(1, 1), t(2, 2), t(0, 1), t(1, 2), t(0, 2)};
}

double von_mises(const Mat3& s) {
  const double a = s(0, 0) - s(1, 1), b = s(1, 1) - s(2, 2), c = s(2, 2) - s(0, 0);
  return std::sqrt(0.5 * (a * a + b * b + c * c) +
                   3.0 * (s(0, 1) * s(0, 1) + s(1, 2) * s(1, 2) + s(0, 2) * s(0, 2)));
}

namespace {

/// ElementFields of `n` elements, all zero (not inverted).
ElementFields zero_fields(std::size_t n) {
  ElementFields out;
  out.strain.assign(6 * n, 0.0);
  out.second_piola.assign(6 * n, 0.0);
  out.cauchy.assign(6 * n, 0.0);
  out.von_mises.assign(n, 0.0);
  out.energy_density.assign(n, 0.0);
  out.inverted.assign(n, 0);
  return out;
}

/// The fields of element i from its 3D strain E, S, energy density W and, for a nonlinear
/// model, F and J = det F (`f` null for linear geometry: σ = S). With J ≤ 0 (StVK past
/// inversion) E, S and W are kept, σ and von Mises are 0 and the element is flagged. The one
/// place a material state becomes output, for tetrahedra and plane-stress triangles.
void store(ElementFields& out, std::size_t i, const Mat3& strain, const Mat3& s, const Mat3* f,
           double j, double w) {
  Mat3 sigma = s;
  if (f != nullptr) {
    if (j > 0.0) {
      sigma = *f * s * f->transpose() / j;
    } else {
      out.inverted[i] = 1;
      sigma.setZero();
    }
  }
  const auto e6 = voigt6(strain), s6 = voigt6(s), c6 = voigt6(sigma);
  for (int c = 0; c < 6; ++c) {
    out.strain[6 * i + c] = e6[c];
    out.second_piola[6 * i + c] = s6[c];
    out.cauchy[6 * i + c] = c6[c];
  }
  out.von_mises[i] = von_mises(sigma);
  out.energy_density[i] = w;
}

/// ElementFields of every element of `problem` (ElasticProblem with TetKernel, 4 nodes of 3
/// DOFs; PlaneStressProblem with TriKernel, 3 nodes of 2 DOFs) at `u`: per element, the
/// kernel's kinematics under the material's model, then `element(model, lame, state, status, i,
/// out)` fills element i from the state and the kinematics' status.
template <template <class, class> class Kernel, int kNodes, int kDim, class P, class Element>
ElementFields sweep(const P& problem, const VecX& u, Element&& element) {
  INCISE_CHECK(u.size() == problem.size(), "element_fields: u has the wrong size");
  const Index ne = problem.num_elements();
  ElementFields out = zero_fields(static_cast<std::size_t>(ne));
  const material::Material& mat = problem.material();
  const material::Lame& lame = mat.lame();
  material::visit_model(mat.model_index(), [&](auto model) {
    using K = Kernel<decltype(model), double>;
    for (Index e = 0; e < ne; ++e) {
      Eigen::Matrix<double, kDim, kNodes> x;
      for (int a = 0; a < kNodes; ++a)
        x.col(a) = u.template segment<kDim>(kDim * problem.cells()(a, e));
      typename K::State st;
      const auto status = K::kinematics(lame, problem.reference(e).z_inv, x, st);
      element(model, lame, st, status, static_cast<std::size_t>(e), out);
    }
  });
  return out;
}

}  // namespace

ElementFields element_fields(const ElasticProblem& problem, const VecX& u) {
  return sweep<TetKernel, 4, 3>(problem, u,
                                [](auto model, const material::Lame& lame, const auto& st, bool ok,
                                   std::size_t i, ElementFields& out) {
                                  using M = decltype(model);
                                  if (!ok) {
                                    out.inverted[i] = 1;
                                    return;
                                  }
                                  const double w = M::energy(lame, st.strain);
                                  if constexpr (M::kLinearGeometry) {
                                    store(out, i, st.strain.e, st.s, nullptr, 1.0, w);
                                  } else {
                                    const double j =
                                        M::kUsesJ ? 1.0 + st.strain.jm1 : st.f.determinant();
                                    store(out, i, st.strain.e, st.s, &st.f, j, w);
                                  }
                                });
}

ElementFields element_fields(const PlaneStressProblem& problem, const VecX& u) {
  using material::PlaneStressStatus;
  return sweep<TriKernel, 3, 2>(
      problem, u,
      [](auto model, const material::Lame& lame, const auto& st, PlaneStressStatus status,
         std::size_t i, ElementFields& out) {
        using M = decltype(model);
        if (status == PlaneStressStatus::kInverted) {
          out.inverted[i] = 1;
          return;
        }
        if (status != PlaneStressStatus::kOk) {  // no state: NaN, never a made-up value
          const double nan = std::numeric_limits<double>::quiet_NaN();
          store(out, i, Mat3::Constant(nan), Mat3::Constant(nan), nullptr, 1.0, nan);
          return;
        }
        const Mat3& strain = st.ps.strain.e;
        const double w = material::PlaneStress<M>::energy(lame, st.ps);
        if constexpr (M::kLinearGeometry) {
          store(out, i, strain, st.ps.s, nullptr, 1.0, w);
        } else {
          const double q2 = 1.0 + 2.0 * strain(2, 2);  // q² = C₃₃
          const double q = q2 > 0.0 ? std::sqrt(q2) : 0.0;
          Mat3 f = Mat3::Zero();
          f.topLeftCorner<2, 2>() = st.f;
          f(2, 2) = q;
          const double j = M::kUsesJ ? 1.0 + st.ps.strain.jm1 : st.f.determinant() * q;
          store(out, i, strain, st.ps.s, &f, q2 > 0.0 ? j : 0.0, w);
        }
      });
}

}  // namespace incise::fem
