#include "element_sweep.hpp"

#include <incise/core/error.hpp>

#include <cmath>

/// \file
/// ElasticProblem's energy, internal forces and gradient sweeps (with and without Π, and fused
/// with K·d).

namespace incise::fem {

using detail::kInf;

EvalStatus ElasticProblem::energy(const VecX& u, double& energy) {
  INCISE_CHECK(u.size() == size(), "energy: u has the wrong size");
  const material::Lame p = material_.lame();
  double sum = 0.0;
  const bool ok = material::visit_model(material_.model_index(), [&](auto m) {
    return sweep(false, sum, [&](const auto& el, auto& w, double& part) INCISE_LAMBDA_INLINE {
      using T = typename std::decay_t<decltype(el)>::Scalar;
      el.gather(u.data(), w.x);
      T e(0);
      if (!TetKernel<decltype(m), T>::energy(p, el.z_inv(), el.volume(), w.x, e)) return false;
      part += el.sum(e);
      return true;
    });
  });
  flops_ += element_flops_.energy * static_cast<std::uint64_t>(num_elements());
  if (!ok) {
    energy = kInf;
    return EvalStatus::kInverted;
  }
  energy = sum - f_ext_.dot(u);
  return std::isfinite(energy) ? EvalStatus::kOk : EvalStatus::kNonFinite;
}

bool ElasticProblem::force_sweep(const VecX& u, VecX& f_int) {
  const material::Lame p = material_.lame();
  f_int.setZero(size());
  double* out = f_int.data();
  double unused = 0.0;  // no energy in this sweep
  const bool ok = material::visit_model(material_.model_index(), [&](auto m) {
    return sweep(true, unused, [&](const auto& el, auto& w, double& /*part*/) INCISE_LAMBDA_INLINE {
      using T = typename std::decay_t<decltype(el)>::Scalar;
      el.gather(u.data(), w.x);
      if (!TetKernel<decltype(m), T>::forces(p, el.z_inv(), el.b(), w.x, w.q)) return false;
      el.add(w.q, out);
      return true;
    });
  });
  flops_ += (element_flops_.force + 12) * static_cast<std::uint64_t>(num_elements());
  if (!ok) f_int.setZero();
  return ok;
}

EvalStatus ElasticProblem::internal_forces(const VecX& u, VecX& f_int) {
  INCISE_CHECK(u.size() == size(), "internal_forces: u has the wrong size");
  if (!force_sweep(u, f_int)) return EvalStatus::kInverted;
  return detail::all_finite(f_int.data(), f_int.size()) ? EvalStatus::kOk : EvalStatus::kNonFinite;
}

EvalStatus ElasticProblem::gradient(const VecX& u, VecX& g, double* energy_out) {
  if (!energy_out) {
    // The forces, then g −= f_ext and the finiteness test in one pass over g (issue 19: the
    // vector passes of an SS22 step without Π).
    INCISE_CHECK(u.size() == size(), "gradient: u has the wrong size");
    if (!force_sweep(u, g)) return EvalStatus::kInverted;
    return detail::subtract_all_finite(g, f_ext_) ? EvalStatus::kOk : EvalStatus::kNonFinite;
  }
  // Gradient and energy in one sweep from the same kinematics (the sums, and so the results,
  // are those of internal_forces() and energy(): same kernels, same element order).
  INCISE_CHECK(u.size() == size(), "gradient: u has the wrong size");
  const material::Lame p = material_.lame();
  g.setZero(size());
  double* out = g.data();
  double sum = 0.0;
  const bool ok = material::visit_model(material_.model_index(), [&](auto m) {
    return sweep(true, sum, [&](const auto& el, auto& w, double& part) INCISE_LAMBDA_INLINE {
      using T = typename std::decay_t<decltype(el)>::Scalar;
      el.gather(u.data(), w.x);
      T e(0);
      if (!TetKernel<decltype(m), T>::forces_and_energy(p, el.z_inv(), el.b(), el.volume(), w.x,
                                                        w.q, e))
        return false;
      el.add(w.q, out);
      part += el.sum(e);
      return true;
    });
  });
  flops_ += (element_flops_.force_and_energy + 13) * static_cast<std::uint64_t>(num_elements());
  if (!ok) {
    g.setZero();
    *energy_out = kInf;
    return EvalStatus::kInverted;
  }
  const bool finite = detail::subtract_all_finite(g, f_ext_);  // g −= f_ext
  *energy_out = sum - f_ext_.dot(u);
  if (!std::isfinite(*energy_out)) return EvalStatus::kNonFinite;
  return finite ? EvalStatus::kOk : EvalStatus::kNonFinite;
}

EvalStatus ElasticProblem::gradient_energy_product(const VecX& u, const VecX& d, VecX& g,
                                                   double& energy, VecX& out) {
  INCISE_CHECK(u.size() == size() && d.size() == size(), "gradient_energy_product: wrong sizes");
  const material::Lame p = material_.lame();
  g.setZero(size());
  out.setZero(size());
  double* gq = g.data();
  double* dst = out.data();
  double sum = 0.0;
  const bool ok = material::visit_model(material_.model_index(), [&](auto m) {
    return sweep(true, sum, [&](const auto& el, auto& w, double& part) INCISE_LAMBDA_INLINE {
      using T = typename std::decay_t<decltype(el)>::Scalar;
      el.gather(u.data(), w.x);
      el.gather(d.data(), w.d);
      T e(0);
      if (!TetKernel<decltype(m), T>::forces_energy_and_product(p, el.z_inv(), el.b(), el.volume(),
                                                                w.x, w.d, w.q, w.dq, e))
        return false;
      el.add(w.q, gq);
      el.add(w.dq, dst);
      part += el.sum(e);
      return true;
    });
  });
  flops_ +=
      (element_flops_.force_energy_and_product + 25) * static_cast<std::uint64_t>(num_elements());
  if (!ok) {
    g.setZero();
    out.setZero();
    energy = kInf;
    return EvalStatus::kInverted;
  }
  g -= f_ext_;
  energy = sum - f_ext_.dot(u);
  if (!std::isfinite(energy)) return EvalStatus::kNonFinite;
  return g.allFinite() && out.allFinite() ? EvalStatus::kOk : EvalStatus::kNonFinite;
}

}  // namespace incise::fem
