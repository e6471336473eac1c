#include "core/surface_query.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

namespace core {

Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                          const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

SurfacePoint TriangleSurface::closest_point(const Eigen::Vector3d& query) const {
  SurfacePoint best;
  best.distance = std::numeric_limits<double>::infinity();
  for (int t = 0; t < triangles.rows(); ++t) {
    const Eigen::Vector3d a = vertices.row(triangles(t, 0));
    const Eigen::Vector3d b = vertices.row(triangles(t, 1));
    const Eigen::Vector3d c = vertices.row(triangles(t, 2));
    const Eigen::Vector3d q = closest_point_on_triangle(query, a, b, c);
    const double d = (q - query).norm();
    if (d < best.distance) {
      best.distance = d;
      best.point = q;
      best.triangle = t;
      best.normal = (b - a).cross(c - a).normalized();
    }
  }
  return best;
}

bool TriangleSurface::contains(const Eigen::Vector3d& x) const {
  // Generalised winding number: the solid angles of the outward triangles seen from x sum to 4 pi inside and 0
  // outside (Van Oosterom & Strackee's formula for one triangle's solid angle).
  double solid_angle = 0.0;
  for (int t = 0; t < triangles.rows(); ++t) {
    const Eigen::Vector3d a = vertices.row(triangles(t, 0)).transpose() - x;
    const Eigen::Vector3d b = vertices.row(triangles(t, 1)).transpose() - x;
    const Eigen::Vector3d c = vertices.row(triangles(t, 2)).transpose() - x;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double numerator = a.dot(b.cross(c));
    const double denominator = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    solid_angle += 2.0 * std::atan2(numerator, denominator);
  }
  return solid_angle > 2.0 * M_PI;
}

double TriangleSurface::ray_hit(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) const {
  // Moller-Trumbore against every triangle.
  double best = std::numeric_limits<double>::infinity();
  for (int t = 0; t < triangles.rows(); ++t) {
    const Eigen::Vector3d a = vertices.row(triangles(t, 0));
    const Eigen::Vector3d e1 = vertices.row(triangles(t, 1)).transpose() - a;
    const Eigen::Vector3d e2 = vertices.row(triangles(t, 2)).transpose() - a;
    const Eigen::Vector3d p = dir.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-300) continue;
    const Eigen::Vector3d r = origin - a;
    const double u = r.dot(p) / det;
    if (u < 0.0 || u > 1.0) continue;
    const Eigen::Vector3d q = r.cross(e1);
    const double v = dir.dot(q) / det;
    if (v < 0.0 || u + v > 1.0) continue;
    const double distance = e2.dot(q) / det;
    if (distance > 0.0) best = std::min(best, distance);
  }
  return best;
}

double TriangleSurface::enclosed_volume() const {
  double v = 0.0;
  for (int t = 0; t < triangles.rows(); ++t) {
    const Eigen::Vector3d a = vertices.row(triangles(t, 0));
    const Eigen::Vector3d b = vertices.row(triangles(t, 1));
    const Eigen::Vector3d c = vertices.row(triangles(t, 2));
    v += a.dot(b.cross(c)) / 6.0;
  }
  return v;
}

double TriangleSurface::area() const {
  double s = 0.0;
  for (int t = 0; t < triangles.rows(); ++t) {
    const Eigen::Vector3d a = vertices.row(triangles(t, 0));
    const Eigen::Vector3d b = vertices.row(triangles(t, 1));
    const Eigen::Vector3d c = vertices.row(triangles(t, 2));
    s += 0.5 * (b - a).cross(c - a).norm();
  }
  return s;
}

int TriangleSurface::count_non_manifold_edges() const {
  std::map<std::pair<int, int>, int> edge_count;
  for (int t = 0; t < triangles.rows(); ++t)
    for (int e = 0; e < 3; ++e) {
      int i = triangles(t, e), j = triangles(t, (e + 1) % 3);
      if (i > j) std::swap(i, j);
      ++edge_count[{i, j}];
    }
  int bad = 0;
  for (const auto& [edge, count] : edge_count)
    if (count != 2) ++bad;
  return bad;
}

}  // namespace core
