#include <incise/core/error.hpp>
#include <incise/mesh/quality.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_set>

namespace incise::mesh {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Angle between u and v in [0, π], accurate near 0 and π.
double angle_between(const Vec3& u, const Vec3& v) {
  return std::atan2(u.cross(v).norm(), u.dot(v));
}

}  // namespace

double signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

double signed_area_xy(const Vec3& a, const Vec3& b, const Vec3& c) {
  return 0.5 * ((b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x()));
}

double triangle_area(const Vec3& a, const Vec3& b, const Vec3& c) {
  return 0.5 * (b - a).cross(c - a).norm();
}

std::array<double, 6> dihedral_angles(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const std::array<const Vec3*, 4> p{&a, &b, &c, &d};
  std::array<double, 6> out{};
  for (int e = 0; e < 6; ++e) {
    const int i = kTetEdges[e][0], j = kTetEdges[e][1];
    int k = -1, l = -1;
    for (int r = 0; r < 4; ++r)
      if (r != i && r != j) (k < 0 ? k : l) = r;
    const Vec3 edge = *p[j] - *p[i];
    const double len2 = edge.squaredNorm();
    Vec3 u = *p[k] - *p[i];
    Vec3 w = *p[l] - *p[i];
    if (len2 > 0) {
      u -= (u.dot(edge) / len2) * edge;
      w -= (w.dot(edge) / len2) * edge;
    }
    out[e] = angle_between(u, w);
  }
  return out;
}

std::array<double, 3> triangle_angles(const Vec3& a, const Vec3& b, const Vec3& c) {
  return {angle_between(b - a, c - a), angle_between(c - b, a - b), angle_between(a - c, b - c)};
}

double aspect_ratio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const std::array<const Vec3*, 4> p{&a, &b, &c, &d};
  double max_edge = 0;
  for (const auto& e : kTetEdges) max_edge = std::max(max_edge, (*p[e[0]] - *p[e[1]]).norm());
  if (!(max_edge > 0)) return 0;
  const double v = std::abs(signed_volume(a, b, c, d));
  // Height over the face opposite vertex r: 3|V| / A_r. The minimum height is over the
  // largest face.
  const double max_face = std::max({triangle_area(b, c, d), triangle_area(a, c, d),
                                    triangle_area(a, b, d), triangle_area(a, b, c)});
  if (!(max_face > 0)) return 0;
  return 3.0 * v / max_face / max_edge;
}

double aspect_ratio(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double la = (b - c).norm(), lb = (a - c).norm(), lc = (a - b).norm();
  const double max_edge = std::max({la, lb, lc});
  if (!(max_edge > 0)) return 0;
  // min height = 2A / max edge.
  return 2.0 * triangle_area(a, b, c) / max_edge / max_edge;
}

double volume_area_quality(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double a0 = triangle_area(b, c, d), a1 = triangle_area(a, c, d),
               a2 = triangle_area(a, b, d), a3 = triangle_area(a, b, c);
  const double a_rms = std::sqrt((a0 * a0 + a1 * a1 + a2 * a2 + a3 * a3) / 4.0);
  if (!(a_rms > 0)) return 0;
  // 3^{7/4} / 2^{3/2}: normalizes the regular tetrahedron to 1 (V = ℓ³/(6√2), A = √3ℓ²/4).
  const double k = std::pow(3.0, 1.75) / std::pow(2.0, 1.5);
  return k * signed_volume(a, b, c, d) / std::pow(a_rms, 1.5);
}

double area_length_quality(const Vec3& a, const Vec3& b, const Vec3& c, bool signed_xy) {
  const double l2 = ((b - c).squaredNorm() + (a - c).squaredNorm() + (a - b).squaredNorm()) / 3.0;
  if (!(l2 > 0)) return 0;
  const double area = signed_xy ? signed_area_xy(a, b, c) : triangle_area(a, b, c);
  return 4.0 / std::sqrt(3.0) * area / l2;
}

const char* to_string(ShapeClass c) {
  switch (c) {
    case ShapeClass::kGood: return "good";
    case ShapeClass::kNeedle: return "needle";
    case ShapeClass::kSpindle: return "spindle";
    case ShapeClass::kSliver: return "sliver";
    case ShapeClass::kCap: return "cap";
    case ShapeClass::kFlat: return "flat";
  }
  return "unknown";
}

ShapeInfo classify_tetrahedron(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d,
                               const ShapeThresholds& t) {
  ShapeInfo info;
  info.aspect_ratio = aspect_ratio(a, b, c, d);
  const auto angles = dihedral_angles(a, b, c, d);
  for (int e = 0; e < 6; ++e) {
    info.large_angle_edge[e] = angles[e] > t.large_angle;
    info.num_large_angles += info.large_angle_edge[e] ? 1 : 0;
  }
  if (info.aspect_ratio >= t.degenerate_aspect_ratio) {
    info.shape = ShapeClass::kGood;
    return info;
  }
  switch (info.num_large_angles) {
    case 0: info.shape = ShapeClass::kNeedle; break;
    case 1: info.shape = ShapeClass::kSpindle; break;
    case 2: info.shape = ShapeClass::kSliver; break;
    case 3: info.shape = ShapeClass::kCap; break;
    default: info.shape = ShapeClass::kFlat; break;
  }
  return info;
}

ShapeInfo classify_triangle(const Vec3& a, const Vec3& b, const Vec3& c, const ShapeThresholds& t) {
  ShapeInfo info;
  info.aspect_ratio = aspect_ratio(a, b, c);
  const auto angles = triangle_angles(a, b, c);
  for (int i = 0; i < 3; ++i) {
    info.large_angle_edge[i] = angles[i] > t.large_angle;
    info.num_large_angles += info.large_angle_edge[i] ? 1 : 0;
  }
  if (info.aspect_ratio >= t.degenerate_aspect_ratio) return info;
  info.shape = info.num_large_angles == 0   ? ShapeClass::kNeedle
               : info.num_large_angles == 1 ? ShapeClass::kCap
                                            : ShapeClass::kFlat;
  return info;
}

Stats summarize(std::vector<double> values) {
  Stats s;
  s.count = static_cast<Index>(values.size());
  if (values.empty()) return s;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  auto rank = [&](double q) {
    const auto r = static_cast<std::size_t>(std::ceil(q * static_cast<double>(n)));
    return values[std::min(n - 1, r == 0 ? 0 : r - 1)];
  };
  s.min = values.front();
  s.max = values.back();
  s.p05 = rank(0.05);
  s.median = rank(0.5);
  s.p95 = rank(0.95);
  double sum = 0;
  for (double v : values) sum += v;
  s.mean = sum / static_cast<double>(n);
  return s;
}

CellQuality cell_quality(const MeshData& m, const ShapeThresholds& t, bool planar) {
  INCISE_CHECK(m.dimension == 2 || m.dimension == 3, "cell_quality: dimension must be 2 or 3");
  INCISE_CHECK(m.cells.rows() == m.dimension + 1, "cell_quality: cells must have d+1 rows");
  const Index n = m.num_cells();
  CellQuality q;
  q.dimension = m.dimension;
  q.size.resize(n);
  q.aspect_ratio.resize(n);
  q.shewchuk.resize(n);
  q.min_angle.resize(n);
  q.max_angle.resize(n);
  q.shape.resize(n);
  for (Index c = 0; c < n; ++c) {
    for (int r = 0; r <= m.dimension; ++r)
      INCISE_CHECK(m.cells(r, c) >= 0 && m.cells(r, c) < m.num_points(),
                   "cell_quality: vertex index out of range");
    const Vec3 a = m.points.col(m.cells(0, c));
    const Vec3 b = m.points.col(m.cells(1, c));
    const Vec3 cc = m.points.col(m.cells(2, c));
    if (m.dimension == 3) {
      const Vec3 d = m.points.col(m.cells(3, c));
      q.size[c] = signed_volume(a, b, cc, d);
      q.shewchuk[c] = volume_area_quality(a, b, cc, d);
      const auto ang = dihedral_angles(a, b, cc, d);
      q.min_angle[c] = *std::min_element(ang.begin(), ang.end());
      q.max_angle[c] = *std::max_element(ang.begin(), ang.end());
      const ShapeInfo s = classify_tetrahedron(a, b, cc, d, t);
      q.aspect_ratio[c] = s.aspect_ratio;
      q.shape[c] = s.shape;
    } else {
      q.size[c] = planar ? signed_area_xy(a, b, cc) : triangle_area(a, b, cc);
      q.shewchuk[c] = area_length_quality(a, b, cc, planar);
      const auto ang = triangle_angles(a, b, cc);
      q.min_angle[c] = *std::min_element(ang.begin(), ang.end());
      q.max_angle[c] = *std::max_element(ang.begin(), ang.end());
      const ShapeInfo s = classify_triangle(a, b, cc, t);
      q.aspect_ratio[c] = s.aspect_ratio;
      q.shape[c] = s.shape;
    }
  }
  return q;
}

QualitySummary summarize_quality(const MeshData& m, const ShapeThresholds& t, bool planar) {
  const CellQuality q = cell_quality(m, t, planar);
  QualitySummary s;
  s.dimension = m.dimension;
  s.num_cells = m.num_cells();
  for (Index c = 0; c < s.num_cells; ++c) {
    s.num_inverted += q.size[c] < 0 ? 1 : 0;
    s.num_zero += q.size[c] == 0 ? 1 : 0;
    s.total_size += q.size[c];
    ++s.shape_counts[static_cast<int>(q.shape[c])];
  }
  auto degrees = [](std::vector<double> v) {
    for (double& x : v) x *= 180.0 / kPi;
    return v;
  };
  s.size = summarize(q.size);
  s.aspect_ratio = summarize(q.aspect_ratio);
  s.shewchuk = summarize(q.shewchuk);
  s.min_angle_deg = summarize(degrees(q.min_angle));
  s.max_angle_deg = summarize(degrees(q.max_angle));
  // Unique edges: key (lo, hi) packed into 64 bits.
  std::unordered_set<std::uint64_t> seen;
  seen.reserve(static_cast<std::size_t>(m.num_cells()) * (m.dimension == 3 ? 2 : 2));
  std::vector<double> lengths;
  for (Index c = 0; c < m.num_cells(); ++c)
    for (int i = 0; i <= m.dimension; ++i)
      for (int j = i + 1; j <= m.dimension; ++j) {
        Index u = m.cells(i, c), v = m.cells(j, c);
        if (u > v) std::swap(u, v);
        const std::uint64_t key =
            (static_cast<std::uint64_t>(static_cast<std::uint32_t>(u)) << 32) |
            static_cast<std::uint32_t>(v);
        if (seen.insert(key).second) lengths.push_back((m.points.col(u) - m.points.col(v)).norm());
      }
  s.edge_length = summarize(std::move(lengths));
  return s;
}

std::array<Vec3, 2> bounding_box(const Eigen::Matrix3Xd& points) {
  if (points.cols() == 0) return {Vec3::Zero(), Vec3::Zero()};
  return {points.rowwise().minCoeff(), points.rowwise().maxCoeff()};
}

}  // namespace incise::mesh
