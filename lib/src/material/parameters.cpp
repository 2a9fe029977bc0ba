#include <incise/core/error.hpp>
#include <incise/material/parameters.hpp>

#include <cmath>
#include <sstream>

namespace incise::material {

namespace {
[[noreturn]] void reject(const char* name, double value, const char* requirement) {
  std::ostringstream os;
  os.precision(17);
  os << "material parameter " << name << " = " << value << " is inadmissible: " << requirement;
  throw ParameterError(os.str());
}
}  // namespace

void validate(const Parameters& p) {
  if (!std::isfinite(p.youngs_modulus) || !(p.youngs_modulus > 0.0))
    reject("E (Young's modulus)", p.youngs_modulus, "must be finite and > 0 Pa");
  if (!std::isfinite(p.poisson_ratio) || !(p.poisson_ratio > -1.0) || !(p.poisson_ratio < 0.5))
    reject("nu (Poisson ratio)", p.poisson_ratio, "must satisfy -1 < nu < 0.5");
  if (!std::isfinite(p.gamma) || !(p.gamma >= 0.0))
    reject("gamma (Veronda-Westmann nonlinearity)", p.gamma, "must be finite and >= 0");
  if (!std::isfinite(p.density) || !(p.density >= 0.0))
    reject("rho (density)", p.density, "must be finite and >= 0 kg/m^3");
}

Lame to_lame(const Parameters& p) {
  validate(p);
  const double e = p.youngs_modulus;
  const double nu = p.poisson_ratio;
  Lame l;
  l.mu = e / (2.0 * (1.0 + nu));
  l.lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
  l.gamma = p.gamma;
  return l;
}

}  // namespace incise::material
