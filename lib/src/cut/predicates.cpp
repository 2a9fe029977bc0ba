#include <incise/cut/predicates.hpp>
#include <incise/mesh/tet_faces.hpp>

#include <algorithm>
#include <cmath>

namespace incise::cut {

double orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (a - d).dot((b - d).cross(c - d));
}

int orient3d_sign(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double det = orient3d(a, b, c, d);
  const double scale = (a - d).norm() * (b - d).norm() * (c - d).norm();
  if (std::abs(det) <= kOrientRelEps * scale) return 0;
  return det > 0 ? 1 : -1;
}

double signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

SegmentHit intersect_segment_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b,
                                      const Vec3& c) {
  SegmentHit out;
  const int sp = orient3d_sign(a, b, c, p);
  const int sq = orient3d_sign(a, b, c, q);
  if (sp == 0 && sq == 0) return out;  // coplanar: not an intersection (policy)
  if (sp == sq) return out;            // strictly on one side
  const int s1 = orient3d_sign(p, q, a, b);
  const int s2 = orient3d_sign(p, q, b, c);
  const int s3 = orient3d_sign(p, q, c, a);
  const bool nonneg = s1 >= 0 && s2 >= 0 && s3 >= 0;
  const bool nonpos = s1 <= 0 && s2 <= 0 && s3 <= 0;
  if (!nonneg && !nonpos) return out;
  out.hit = true;
  if (sp == 0) {
    out.t = 0.0;
  } else if (sq == 0) {
    out.t = 1.0;
  } else {
    const double dp = orient3d(a, b, c, p);
    const double dq = orient3d(a, b, c, q);
    out.t = std::clamp(dp / (dp - dq), 0.0, 1.0);
  }
  return out;
}

bool barycentric(const Vec3& p, const Vec3 (&t)[4], double (&lambda)[4]) {
  Mat3 m;
  m.col(0) = t[1] - t[0];
  m.col(1) = t[2] - t[0];
  m.col(2) = t[3] - t[0];
  const double det = m.determinant();
  const double scale = m.col(0).norm() * m.col(1).norm() * m.col(2).norm();
  if (!(std::abs(det) > kOrientRelEps * scale)) return false;
  const Vec3 l = m.inverse() * (p - t[0]);
  lambda[1] = l[0];
  lambda[2] = l[1];
  lambda[3] = l[2];
  lambda[0] = 1.0 - l[0] - l[1] - l[2];
  return true;
}

bool triangle_meets_tetrahedron(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3 (&t)[4]) {
  static constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  for (const auto& e : kEdges) {
    if (intersect_segment_triangle(t[e[0]], t[e[1]], a, b, c).hit) return true;
  }
  const Vec3* tri[3] = {&a, &b, &c};
  for (int i = 0; i < 3; ++i) {
    const Vec3& p = *tri[i];
    const Vec3& q = *tri[(i + 1) % 3];
    for (const auto& f : mesh::kTetFace) {
      if (intersect_segment_triangle(p, q, t[f[0]], t[f[1]], t[f[2]]).hit) return true;
    }
  }
  double lambda[4];
  if (barycentric(a, t, lambda)) {
    bool inside = true;
    for (double l : lambda) inside = inside && l >= 0.0;
    if (inside) return true;
  }
  return false;
}

}  // namespace incise::cut
