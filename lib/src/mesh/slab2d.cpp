#include <incise/core/error.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/mesh/slab2d.hpp>

#include <cmath>
#include <string>

namespace incise::mesh {

namespace {

int divisions(double l, double h, const char* what) {
  const double n = l / h;
  const double r = std::round(n);
  INCISE_CHECK_PARAM(
      r >= 1.0 && std::abs(n - r) <= 1e-9 * r,
      std::string(what) + " / h must be a positive integer, got " + std::to_string(n));
  return static_cast<int>(r);
}

}  // namespace

double thesis_slab_spacing(int k) {
  INCISE_CHECK_PARAM(k >= 1 && k <= 7, "slab level k must be 1..7, got " + std::to_string(k));
  return std::ldexp(0.1, -k);
}

MeshData make_right_triangle_slab(double lx, double ly, double h) {
  INCISE_CHECK_PARAM(std::isfinite(lx) && lx > 0.0, "lx must be finite and > 0");
  INCISE_CHECK_PARAM(std::isfinite(ly) && ly > 0.0, "ly must be finite and > 0");
  INCISE_CHECK_PARAM(std::isfinite(h) && h > 0.0, "h must be finite and > 0");
  return make_rectangle(divisions(lx, h, "lx"), divisions(ly, h, "ly"), lx, ly,
                        GridDiagonal::kAlternating);
}

MeshData make_thesis_slab(int k) {
  return make_right_triangle_slab(0.1, 0.1, thesis_slab_spacing(k));
}

}  // namespace incise::mesh
