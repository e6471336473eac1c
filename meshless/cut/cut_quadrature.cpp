#include "meshless/cut/cut_quadrature.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace meshless {
namespace {

constexpr double kOnPlane = core::RuledSurface::kOnCutTolerance;

/// Signed distances of points to panel j's plane, with points on the plane moved to exactly 0 (they count as the
/// s > 0 side, see the header).
template <std::size_t N>
std::array<double, N> plane_distances(const core::CutPanel& p, const std::array<Eigen::Vector3d, N>& v) {
  std::array<double, N> d{};
  for (std::size_t k = 0; k < N; ++k) {
    d[k] = (v[k] - p.origin).dot(p.normal);
    if (std::abs(d[k]) <= kOnPlane) d[k] = 0.0;
  }
  return d;
}

inline bool positive(double d) { return d >= 0.0; }  // on the plane counts as the s > 0 side

template <std::size_t N>
bool straddles(const std::array<double, N>& d) {
  bool pos = false, neg = false;
  for (double x : d) (positive(x) ? pos : neg) = true;
  return pos && neg;
}

/// The point where edge (a, b) meets the plane, from the signed distances (one of which is negative).
Eigen::Vector3d edge_point(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double da, double db) {
  const double t = da / (da - db);
  return a + t * (b - a);
}

/// Panel coordinates (a, z) of a point in the panel's plane.
Eigen::Vector2d to_panel(const core::CutPanel& p, const Eigen::Vector3d& x, const Eigen::Vector3d& direction) {
  return Eigen::Vector2d((x - p.origin).dot(p.tangent), x.dot(direction));
}

Eigen::Vector3d from_panel(const core::CutPanel& p, const Eigen::Vector2d& az, const Eigen::Vector3d& direction) {
  return p.origin + az.x() * p.tangent + az.y() * direction;
}

/// Sutherland-Hodgman: keep the part of a convex polygon where f(point) <= 0, f affine.
template <class F>
std::vector<Eigen::Vector2d> clip(const std::vector<Eigen::Vector2d>& polygon, const F& f) {
  std::vector<Eigen::Vector2d> out;
  const std::size_t n = polygon.size();
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector2d& a = polygon[k];
    const Eigen::Vector2d& b = polygon[(k + 1) % n];
    const double fa = f(a), fb = f(b);
    if (fa <= 0.0) out.push_back(a);
    if ((fa < 0.0 && fb > 0.0) || (fa > 0.0 && fb < 0.0)) out.push_back(a + fa / (fa - fb) * (b - a));
  }
  return out;
}

/// The polygon clipped to the panel's strip: 0 <= a <= length, z below the bottom edge.
std::vector<Eigen::Vector2d> clip_to_panel(const core::CutPanel& p, std::vector<Eigen::Vector2d> polygon) {
  const double slope = (p.bottom_end - p.bottom_start) / p.length;
  polygon = clip(polygon, [](const Eigen::Vector2d& q) { return -q.x(); });
  polygon = clip(polygon, [&](const Eigen::Vector2d& q) { return q.x() - p.length; });
  polygon = clip(polygon, [&](const Eigen::Vector2d& q) { return q.y() - (p.bottom_start + slope * q.x()); });
  return polygon;
}

double polygon_area(const std::vector<Eigen::Vector2d>& polygon) {
  double twice = 0.0;
  for (std::size_t k = 0; k < polygon.size(); ++k) {
    const Eigen::Vector2d& a = polygon[k];
    const Eigen::Vector2d& b = polygon[(k + 1) % polygon.size()];
    twice += a.x() * b.y() - a.y() * b.x();
  }
  return 0.5 * std::abs(twice);
}

/// Order the (coplanar, convex-position) points around their centroid in panel coordinates.
std::vector<Eigen::Vector2d> convex_order(std::vector<Eigen::Vector2d> points) {
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (const auto& q : points) c += q / static_cast<double>(points.size());
  std::sort(points.begin(), points.end(), [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return std::atan2(a.y() - c.y(), a.x() - c.x()) < std::atan2(b.y() - c.y(), b.x() - c.x());
  });
  return points;
}

/// A prism with triangles (p0, p1, p2) and (q0, q1, q2), p_k joined to q_k by an edge and planar side faces, as
/// three tetrahedra (the standard split; valid for any convex prism with planar quadrilateral sides).
void add_prism(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& p2,
               const Eigen::Vector3d& q0, const Eigen::Vector3d& q1, const Eigen::Vector3d& q2,
               std::vector<TetVertices>* out) {
  out->push_back({p0, p1, p2, q0});
  out->push_back({p1, p2, q0, q1});
  out->push_back({p2, q0, q1, q2});
}

/// Split one tetrahedron by one plane (distances d, at least one vertex on each side).
void split_by_plane(const TetVertices& t, const std::array<double, 4>& d, std::vector<TetVertices>* out) {
  std::vector<int> pos, neg;
  for (int k = 0; k < 4; ++k) (positive(d[k]) ? pos : neg).push_back(k);
  const auto cut = [&](int a, int b) { return edge_point(t[a], t[b], d[a], d[b]); };
  if (pos.size() == 1 || neg.size() == 1) {
    // One vertex A alone on its side: the tetrahedron (A, AB, AC, AD) and the prism (AB, AC, AD)-(B, C, D).
    const int a = pos.size() == 1 ? pos[0] : neg[0];
    const std::vector<int>& others = pos.size() == 1 ? neg : pos;
    const int b = others[0], c = others[1], e = others[2];
    const Eigen::Vector3d ab = cut(a, b), ac = cut(a, c), ae = cut(a, e);
    out->push_back({t[a], ab, ac, ae});
    add_prism(ab, ac, ae, t[b], t[c], t[e], out);
  } else {
    // Two and two: A, B on one side, C, D on the other. Prisms (A, AC, AD)-(B, BC, BD) and (C, AC, BC)-(D, AD, BD).
    const int a = pos[0], b = pos[1], c = neg[0], e = neg[1];
    const Eigen::Vector3d ac = cut(a, c), ae = cut(a, e), bc = cut(b, c), be = cut(b, e);
    add_prism(t[a], ac, ae, t[b], bc, be, out);
    add_prism(t[c], ac, bc, t[e], ae, be, out);
  }
}

void split_by_plane(const TriangleVertices& t, const std::array<double, 3>& d, std::vector<TriangleVertices>* out) {
  std::vector<int> pos, neg;
  for (int k = 0; k < 3; ++k) (positive(d[k]) ? pos : neg).push_back(k);
  const int a = pos.size() == 1 ? pos[0] : neg[0];
  const std::vector<int>& others = pos.size() == 1 ? neg : pos;
  const int b = others[0], c = others[1];
  const Eigen::Vector3d ab = edge_point(t[a], t[b], d[a], d[b]), ac = edge_point(t[a], t[c], d[a], d[c]);
  out->push_back({t[a], ab, ac});
  out->push_back({ab, t[b], t[c]});
  out->push_back({ab, t[c], ac});
}

}  // namespace

double tet_volume(const TetVertices& t) { return std::abs((t[1] - t[0]).cross(t[2] - t[0]).dot(t[3] - t[0])) / 6.0; }

double triangle_area(const TriangleVertices& t) { return 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).norm(); }

std::vector<int> panels_crossing_tet(const core::RuledSurface& cut, const TetVertices& tet,
                                     std::vector<std::vector<Eigen::Vector3d>>* lips) {
  static constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  std::vector<int> panels;
  if (lips) lips->clear();
  const double scale2 = std::max({(tet[1] - tet[0]).squaredNorm(), (tet[2] - tet[0]).squaredNorm(),
                                  (tet[3] - tet[0]).squaredNorm()});
  for (int j = 0; j < cut.num_panels(); ++j) {
    const core::CutPanel p = cut.panel(j);
    const std::array<double, 4> d = plane_distances(p, tet);
    if (!straddles(d)) continue;
    std::vector<Eigen::Vector2d> polygon;
    for (const auto& e : kEdges)
      if (positive(d[e[0]]) != positive(d[e[1]]))
        polygon.push_back(to_panel(p, edge_point(tet[e[0]], tet[e[1]], d[e[0]], d[e[1]]), cut.direction()));
    polygon = clip_to_panel(p, convex_order(std::move(polygon)));
    if (polygon.size() < 3 || polygon_area(polygon) <= 1e-12 * scale2) continue;
    panels.push_back(j);
    if (lips) {
      std::vector<Eigen::Vector3d> lip;
      for (const auto& q : polygon) lip.push_back(from_panel(p, q, cut.direction()));
      lips->push_back(std::move(lip));
    }
  }
  return panels;
}

std::vector<int> panels_crossing_triangle(const core::RuledSurface& cut, const TriangleVertices& triangle) {
  std::vector<int> panels;
  const double scale = std::max({(triangle[1] - triangle[0]).norm(), (triangle[2] - triangle[0]).norm()});
  for (int j = 0; j < cut.num_panels(); ++j) {
    const core::CutPanel p = cut.panel(j);
    const std::array<double, 3> d = plane_distances(p, triangle);
    if (!straddles(d)) continue;
    // The plane meets the triangle in a segment; keep the triangle when that segment overlaps the panel. A segment
    // is a degenerate polygon: clip it as the two-point polygon and measure what is left.
    std::vector<Eigen::Vector2d> segment;
    for (int k = 0; k < 3; ++k) {
      const int a = k, b = (k + 1) % 3;
      if (positive(d[a]) != positive(d[b]))
        segment.push_back(to_panel(p, edge_point(triangle[a], triangle[b], d[a], d[b]), cut.direction()));
    }
    segment = clip_to_panel(p, segment);
    double length = 0.0;
    for (std::size_t k = 0; k + 1 < segment.size(); ++k) length = std::max(length, (segment[k + 1] - segment[k]).norm());
    if (length > 1e-9 * scale) panels.push_back(j);
  }
  return panels;
}

std::vector<TetVertices> split_tet(const core::RuledSurface& cut, const std::vector<int>& panels, const TetVertices& tet) {
  const double volume = tet_volume(tet);
  std::vector<TetVertices> pieces{tet};
  for (int j : panels) {
    const core::CutPanel p = cut.panel(j);
    std::vector<TetVertices> next;
    for (const TetVertices& piece : pieces) {
      const std::array<double, 4> d = plane_distances(p, piece);
      if (straddles(d)) split_by_plane(piece, d, &next);
      else next.push_back(piece);
    }
    pieces.clear();
    for (const TetVertices& piece : next)
      if (tet_volume(piece) > 1e-12 * volume) pieces.push_back(piece);
  }
  return pieces;
}

std::vector<TriangleVertices> split_triangle(const core::RuledSurface& cut, const std::vector<int>& panels,
                                             const TriangleVertices& triangle) {
  const double area = triangle_area(triangle);
  std::vector<TriangleVertices> pieces{triangle};
  for (int j : panels) {
    const core::CutPanel p = cut.panel(j);
    std::vector<TriangleVertices> next;
    for (const TriangleVertices& piece : pieces) {
      const std::array<double, 3> d = plane_distances(p, piece);
      if (straddles(d)) split_by_plane(piece, d, &next);
      else next.push_back(piece);
    }
    pieces.clear();
    for (const TriangleVertices& piece : next)
      if (triangle_area(piece) > 1e-12 * area) pieces.push_back(piece);
  }
  return pieces;
}

}  // namespace meshless
