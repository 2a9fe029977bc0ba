#include <incise/core/error.hpp>
#include <incise/mesh/tet_faces.hpp>
#include <incise/needle/needle3d.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

namespace incise::needle {

namespace {

Vec3 default_normal(const Vec3& t) {
  int k = 0;
  for (int i = 1; i < 3; ++i)
    if (std::abs(t(i)) < std::abs(t(k))) k = i;
  const Vec3 e = Vec3::Unit(k);
  return (e - e.dot(t) * t).normalized();
}

void check_tip_direction(const Vec3& tip, const Vec3& direction) {
  INCISE_CHECK_PARAM(tip.allFinite(), "needle tip must be finite");
  INCISE_CHECK_PARAM(direction.allFinite() && direction.norm() > 0.0,
                     "needle direction must be finite and non-zero");
}

}  // namespace

NeedlePose3D NeedlePose3D::make(const Vec3& tip, const Vec3& direction, double length,
                                double radius) {
  check_tip_direction(tip, direction);
  NeedlePose3D p;
  p.tip = tip;
  p.direction = direction.normalized();
  p.normal = default_normal(p.direction);
  p.length = length;
  p.radius = radius;
  p.validate();
  return p;
}

void NeedlePose3D::validate() const {
  check_tip_direction(tip, direction);
  INCISE_CHECK_PARAM(normal.allFinite() && normal.norm() > 0.0,
                     "needle normal n1 must be finite and non-zero");
  INCISE_CHECK_PARAM(std::abs(normal.normalized().dot(direction.normalized())) <= 1e-9,
                     "needle normal n1 must be perpendicular to the direction");
  INCISE_CHECK_PARAM(std::isfinite(length) && length > 0.0,
                     "needle length must be finite and > 0, got " + std::to_string(length));
  INCISE_CHECK_PARAM(std::isfinite(radius) && radius > 0.0,
                     "needle radius must be finite and > 0, got " + std::to_string(radius));
}

Mat3 NeedlePose3D::frame() const {
  Mat3 r;
  r << direction, normal, normal2();
  return r;
}

NeedleCoordinates3D NeedlePose3D::coordinates(const Vec3& x) const {
  NeedleCoordinates3D c;
  const Vec3 d = x - tip;
  c.s = -d.dot(direction);
  c.perp = Vec2(d.dot(normal), d.dot(normal2()));
  return c;
}

Vec3 NeedlePose3D::point(const NeedleCoordinates3D& c) const {
  return tip - c.s * direction + c.perp(0) * normal + c.perp(1) * normal2();
}

NeedlePose3D NeedlePose3D::moved(const Vec3& new_tip, const Vec3& new_direction) const {
  check_tip_direction(new_tip, new_direction);
  NeedlePose3D p = *this;
  p.tip = new_tip;
  p.direction = new_direction.normalized();
  const double c = direction.dot(p.direction);
  Vec3 n;
  if (c > -1.0 + 1e-12) {
    // Rodrigues for the least rotation taking t to t': x ↦ c·x + v × x + v(v·x)/(1 + c),
    // v = t × t'.
    const Vec3 v = direction.cross(p.direction);
    n = c * normal + v.cross(normal) + v * (v.dot(normal) / (1.0 + c));
  } else {
    n = normal;  // half turn about n1
  }
  p.normal = (n - n.dot(p.direction) * p.direction).normalized();
  p.validate();
  return p;
}

ShaftApproach shaft_approach(const NeedlePose3D& pose, const Vec3& a, const Vec3& b) {
  // Closest points of segments a + α·e (α ∈ [0,1]) and p0 + β·d (β ∈ [0,1]), p0 = base,
  // d = L·t (Ericson, Real-Time Collision Detection §5.1.9).
  const Vec3 p0 = pose.base(), d = pose.tip - p0, e = b - a, w = a - p0;
  const double ee = e.dot(e), dd = d.dot(d), ed = e.dot(d), ew = e.dot(w), dw = d.dot(w);
  double alpha = 0.0, beta = 0.0;
  const double den = ee * dd - ed * ed;
  if (ee <= 0.0) {
    beta = std::clamp(dw / dd, 0.0, 1.0);
  } else {
    alpha = den > 1e-14 * ee * dd ? std::clamp((ed * dw - dd * ew) / den, 0.0, 1.0) : 0.0;
    beta = (ed * alpha + dw) / dd;
    if (beta < 0.0) {
      beta = 0.0;
      alpha = std::clamp(-ew / ee, 0.0, 1.0);
    } else if (beta > 1.0) {
      beta = 1.0;
      alpha = std::clamp((ed - ew) / ee, 0.0, 1.0);
    }
  }
  ShaftApproach r;
  r.alpha = alpha;
  r.s = (1.0 - beta) * pose.length;
  r.distance = ((a + alpha * e) - (p0 + beta * d)).norm();
  return r;
}

mesh::CellMatrix needle_surface(const mesh::CellMatrix& tets, const std::vector<char>& is_needle) {
  INCISE_CHECK(tets.rows() == 4, "needle_surface: tets need 4 rows");
  const auto n = static_cast<Index>(is_needle.size());
  // (sorted face, whether its tetrahedron has four needle vertices)
  std::vector<std::pair<std::array<Index, 3>, char>> faces;
  for (Eigen::Index c = 0; c < tets.cols(); ++c) {
    int count = 0;
    for (int i = 0; i < 4; ++i) {
      const Index v = tets(i, c);
      INCISE_CHECK(v >= 0 && v < n,
                   "needle_surface: vertex " + std::to_string(v) + " out of range of is_needle");
      count += is_needle[static_cast<std::size_t>(v)] ? 1 : 0;
    }
    if (count < 3) continue;
    for (const auto& f : mesh::kTetFace) {
      std::array<Index, 3> t{tets(f[0], c), tets(f[1], c), tets(f[2], c)};
      if (!is_needle[static_cast<std::size_t>(t[0])] ||
          !is_needle[static_cast<std::size_t>(t[1])] || !is_needle[static_cast<std::size_t>(t[2])])
        continue;
      std::sort(t.begin(), t.end());
      faces.push_back({t, static_cast<char>(count == 4)});
    }
  }
  std::sort(faces.begin(), faces.end());
  std::vector<std::array<Index, 3>> kept;
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i;
    bool all_inside = true;
    for (; j < faces.size() && faces[j].first == faces[i].first; ++j)
      all_inside = all_inside && faces[j].second;
    if (!all_inside) kept.push_back(faces[i].first);
    i = j;
  }
  mesh::CellMatrix out(3, static_cast<Eigen::Index>(kept.size()));
  for (std::size_t k = 0; k < kept.size(); ++k)
    for (int i = 0; i < 3; ++i)
      out(i, static_cast<Eigen::Index>(k)) = kept[k][static_cast<std::size_t>(i)];
  return out;
}

std::vector<double> needle_node_areas(const Eigen::Matrix3Xd& x, const mesh::CellMatrix& faces,
                                      const std::vector<Index>& vertices) {
  std::vector<double> per_vertex(static_cast<std::size_t>(x.cols()), 0.0);
  for (Eigen::Index f = 0; f < faces.cols(); ++f) {
    const Vec3 a = x.col(faces(0, f)), b = x.col(faces(1, f)), c = x.col(faces(2, f));
    const double third = (b - a).cross(c - a).norm() / 6.0;
    for (int i = 0; i < 3; ++i) per_vertex[static_cast<std::size_t>(faces(i, f))] += third;
  }
  std::vector<double> out;
  out.reserve(vertices.size());
  for (const Index v : vertices) out.push_back(per_vertex[static_cast<std::size_t>(v)]);
  return out;
}

}  // namespace incise::needle
