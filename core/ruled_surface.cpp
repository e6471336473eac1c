#include "core/ruled_surface.hpp"

#include <Eigen/Geometry>
#include <limits>
#include <stdexcept>

#include "core/surface_query.hpp"

namespace core {

RuledSurface::RuledSurface(std::vector<Eigen::Vector3d> top, const Eigen::Vector3d& direction, double depth)
    : top_(std::move(top)), direction_(direction.normalized()), depth_(depth) {
  if (top_.size() < 2) throw std::invalid_argument("RuledSurface: need at least two polyline points");
  if (!(depth_ > 0.0)) throw std::invalid_argument("RuledSurface: depth must be positive");
  for (int i = 0; i < num_panels(); ++i) {
    const Eigen::Vector3d seg = top_[i + 1] - top_[i];
    if (seg.cross(direction_).norm() < 1e-9 * std::max(seg.norm(), 1e-12))
      throw std::invalid_argument("RuledSurface: a polyline segment is parallel to the depth direction");
  }
}

Eigen::Vector3d RuledSurface::panel_normal(int panel) const {
  const Eigen::Vector3d seg = top_[panel + 1] - top_[panel];
  return seg.cross(direction_).normalized();
}

CutCoordinates RuledSurface::coordinates(const Eigen::Vector3d& x, int panel) const {
  // Panel frame: e_depth = direction, e_zeta = segment made orthogonal to it, n = e_zeta x e_depth.
  const Eigen::Vector3d a = top_[panel];
  const Eigen::Vector3d seg = top_[panel + 1] - a;
  const Eigen::Vector3d e_zeta = (seg - seg.dot(direction_) * direction_).normalized();
  const Eigen::Vector3d n = e_zeta.cross(direction_);
  const Eigen::Vector3d r = x - a;
  CutCoordinates c;
  c.panel = panel;
  c.s = r.dot(n);
  c.zeta = r.dot(e_zeta);
  c.length = seg.dot(e_zeta);
  // Depth is measured from the (sheared) top line, so the panel is exactly 0 <= depth <= depth_.
  const double t = c.length > 0 ? c.zeta / c.length : 0.0;
  c.depth = r.dot(direction_) - t * seg.dot(direction_);
  return c;
}

double RuledSurface::distance(const Eigen::Vector3d& x) const {
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < num_panels(); ++i) {
    const Eigen::Vector3d a = top_[i], b = top_[i + 1];
    const Eigen::Vector3d c = b + depth_ * direction_, d = a + depth_ * direction_;
    best = std::min(best, (closest_point_on_triangle(x, a, b, c) - x).norm());
    best = std::min(best, (closest_point_on_triangle(x, a, c, d) - x).norm());
  }
  return best;
}

CutCoordinates RuledSurface::nearest_panel_coordinates(const Eigen::Vector3d& x) const {
  int best_panel = 0;
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < num_panels(); ++i) {
    const Eigen::Vector3d a = top_[i], b = top_[i + 1];
    const Eigen::Vector3d c = b + depth_ * direction_, d = a + depth_ * direction_;
    const double di = std::min((closest_point_on_triangle(x, a, b, c) - x).norm(),
                               (closest_point_on_triangle(x, a, c, d) - x).norm());
    if (di < best) {
      best = di;
      best_panel = i;
    }
  }
  return coordinates(x, best_panel);
}

void RuledSurface::triangulate(PointMatrix* vertices, TriMatrix* triangles, double extend) const {
  const int n = static_cast<int>(top_.size());
  vertices->resize(2 * n, 3);
  for (int i = 0; i < n; ++i) {
    vertices->row(i) = (top_[i] - extend * direction_).transpose();
    vertices->row(n + i) = (top_[i] + depth_ * direction_).transpose();
  }
  triangles->resize(2 * num_panels(), 3);
  for (int i = 0; i < num_panels(); ++i) {
    triangles->row(2 * i) << i, i + 1, n + i + 1;
    triangles->row(2 * i + 1) << i, n + i + 1, n + i;
  }
}

double RuledSurface::area() const {
  double s = 0.0;
  for (int i = 0; i < num_panels(); ++i)
    s += (top_[i + 1] - top_[i]).cross(direction_).norm() * depth_;
  return s;
}

}  // namespace core
