#include <incise/core/error.hpp>
#include <incise/material/material.hpp>

#include <limits>
#include <sstream>

namespace incise::material {

std::vector<std::string> registered_material_names() {
  std::vector<std::string> names;
  for (int i = 0; i < kNumModels; ++i)
    names.emplace_back(visit_model(i, [](auto m) { return std::string(decltype(m)::kName); }));
  return names;
}

int model_index(const std::string& name) {
  const std::vector<std::string> names = registered_material_names();
  for (int i = 0; i < static_cast<int>(names.size()); ++i)
    if (names[static_cast<std::size_t>(i)] == name) return i;
  std::ostringstream os;
  os << "unknown material model '" << name << "'; registered models:";
  for (const auto& n : names) os << " " << n;
  throw ParameterError(os.str());
}

Material::Material(const std::string& name, const Parameters& p)
    : name_(name), index_(material::model_index(name)), parameters_(p), lame_(to_lame(p)) {}

bool Material::linear_geometry() const {
  return visit_model(index_, [](auto m) { return decltype(m)::kLinearGeometry; });
}

bool Material::defined_when_inverted() const {
  return visit_model(index_, [](auto m) { return decltype(m)::kDefinedWhenInverted; });
}

double Material::energy_density(const Mat3& c) const {
  return visit_model(index_, [&](auto m) {
    using M = decltype(m);
    return M::energy(lame_, strain_from_c<M>(c));
  });
}

Mat3 Material::stress(const Mat3& c) const {
  return visit_model(index_, [&](auto m) {
    using M = decltype(m);
    MaterialState<double> st;
    Mat3 s;
    M::stress(lame_, strain_from_c<M>(c), st, s);
    return s;
  });
}

Mat3 Material::stress_derivative(const Mat3& c, const Mat3& h) const {
  return visit_model(index_, [&](auto m) {
    using M = decltype(m);
    MaterialState<double> st;
    Mat3 s;
    M::stress(lame_, strain_from_c<M>(c), st, s);
    return Mat3(M::stress_derivative(lame_, st, h));
  });
}

TangentModuli<double> Material::moduli(const Mat3& c) const {
  return visit_model(index_, [&](auto m) {
    using M = decltype(m);
    MaterialState<double> st;
    Mat3 s;
    M::stress(lame_, strain_from_c<M>(c), st, s);
    return M::moduli(lame_, st);
  });
}

PointEvaluation Material::evaluate(const Mat3& f) const {
  // G = F − I is exact for diagonal entries in [½, 2] (Sterbenz); the strain is computed from G.
  const Mat3 g = f - Mat3::Identity();
  return visit_model(index_, [&](auto m) {
    using M = decltype(m);
    PointEvaluation out;
    Strain<double> s;
    strain_from_gradient<M>(g, f, s);
    if constexpr (!M::kDefinedWhenInverted) {
      if (!(s.jm1 > -1.0)) {
        out.inverted = true;
        out.energy = std::numeric_limits<double>::infinity();
        out.first_piola.setZero();
        out.second_piola.setZero();
        return out;
      }
    }
    MaterialState<double> st;
    out.energy = M::energy(lame_, s);
    M::stress(lame_, s, st, out.second_piola);
    out.first_piola = M::kLinearGeometry ? out.second_piola : Mat3(f * out.second_piola);
    return out;
  });
}

}  // namespace incise::material
