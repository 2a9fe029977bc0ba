#include <incise/cut/cut_mesh.hpp>
#include <incise/cut/tet_shape.hpp>

#include <algorithm>
#include <cmath>

namespace incise::cut {

namespace {
constexpr double kPi = 3.14159265358979323846;
}  // namespace

TetShape tet_shape(const std::array<Vec3, 4>& p) {
  TetShape s;
  const double vol6 = (p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0]));
  double max_edge = 0.0;
  double min_edge = 0.0;
  for (int k = 0; k < 6; ++k) {
    const double len =
        (p[static_cast<size_t>(kTetEdge[k][0])] - p[static_cast<size_t>(kTetEdge[k][1])]).norm();
    if (k == 0 || len < min_edge) {
      min_edge = len;
      s.shortest_edge = k;
    }
    max_edge = std::max(max_edge, len);
  }
  // Face areas (×2) and outward normals; height over face j = vol6 / |area2_j|.
  std::array<Vec3, 4> normal;
  double min_height = 0.0;
  for (int j = 0; j < 4; ++j) {
    const Vec3& a = p[static_cast<size_t>(kTetFace[j][0])];
    const Vec3& b = p[static_cast<size_t>(kTetFace[j][1])];
    const Vec3& c = p[static_cast<size_t>(kTetFace[j][2])];
    const Vec3 n = (b - a).cross(c - a);
    const double area2 = n.norm();
    normal[static_cast<size_t>(j)] = area2 > 0 ? Vec3(n / area2) : Vec3::Zero();
    const double h = area2 > 0 ? vol6 / area2 : 0.0;
    if (j == 0 || h < min_height) min_height = h;
  }
  s.aspect_ratio = max_edge > 0 ? min_height / max_edge : 0.0;
  // Edge (i,k) lies on the two faces opposite the other two nodes; interior dihedral angle
  // = π − angle between the outward normals.
  for (int k = 0; k < 6; ++k) {
    int others[2];
    int m = 0;
    for (int j = 0; j < 4; ++j) {
      if (j != kTetEdge[k][0] && j != kTetEdge[k][1]) others[m++] = j;
    }
    const double c = std::clamp(
        normal[static_cast<size_t>(others[0])].dot(normal[static_cast<size_t>(others[1])]), -1.0,
        1.0);
    s.dihedral[static_cast<size_t>(k)] = kPi - std::acos(c);
  }
  return s;
}

DegeneracyShape classify(const TetShape& s, double large_angle, std::array<int, 6>& large_edges,
                         int& num_large) {
  num_large = 0;
  for (int k = 0; k < 6; ++k) {
    if (s.dihedral[static_cast<size_t>(k)] > large_angle)
      large_edges[static_cast<size_t>(num_large++)] = k;
  }
  std::sort(large_edges.begin(), large_edges.begin() + num_large, [&s](int a, int b) {
    return s.dihedral[static_cast<size_t>(a)] > s.dihedral[static_cast<size_t>(b)];
  });
  if (num_large == 0) return DegeneracyShape::kNeedle;
  if (num_large == 1) return DegeneracyShape::kSpindle;
  if (num_large == 2) return DegeneracyShape::kSliver;
  return DegeneracyShape::kCap;
}

}  // namespace incise::cut
