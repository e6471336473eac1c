#include "meshless/lrpim/local_quadrature.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/surface_query.hpp"
#include "meshless/efg/gauss_quadrature_tet.hpp"
#include "meshless/mls/cubic_spline_weight.hpp"

namespace meshless::lrpim {

void gauss_legendre(int n, std::vector<double>* nodes, std::vector<double>* weights) {
  if (n < 1) throw std::invalid_argument("gauss_legendre: need at least one point");
  nodes->assign(n, 0.0);
  weights->assign(n, 0.0);
  for (int i = 0; i < (n + 1) / 2; ++i) {
    double x = std::cos(M_PI * (i + 0.75) / (n + 0.5)), dp = 1.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = x;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2 * k - 1) * x * p1 - (k - 1) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (x * p1 - p0) / (x * x - 1.0);
      const double dx = p1 / dp;
      x -= dx;
      if (std::abs(dx) < 1e-16) break;
    }
    (*nodes)[i] = -x;
    (*nodes)[n - 1 - i] = x;
    (*weights)[i] = (*weights)[n - 1 - i] = 2.0 / ((1.0 - x * x) * dp * dp);
  }
}

namespace {

// Gauss points of [a, b] appended as (r, weight).
void segment(double a, double b, const std::vector<double>& gx, const std::vector<double>& gw,
             std::vector<std::pair<double, double>>* out) {
  if (!(b > a)) return;
  for (size_t k = 0; k < gx.size(); ++k) out->emplace_back(0.5 * (a + b) + 0.5 * (b - a) * gx[k], 0.5 * (b - a) * gw[k]);
}

LocalPoint test_point(const Eigen::Vector3d& centre, double r_q, const Eigen::Vector3d& x, double weight) {
  LocalPoint p;
  p.x = x;
  p.weight = weight;
  const Eigen::Vector3d d = x - centre;
  const double r = d.norm();
  const WeightAndSlope ws = cubic_spline_weight_with_slope(r / r_q);
  p.v = ws.w;
  p.dv = r > 0.0 ? Eigen::Vector3d(ws.dw_ds / (r_q * r) * d) : Eigen::Vector3d::Zero();
  return p;
}

// The sphere rule over whatever pieces of each ray lie inside: segments(dir, pieces) fills the pieces within r_q.
template <class Segments>
std::vector<LocalPoint> sphere_points_of(const Eigen::Vector3d& centre, double r_q, const LocalQuadratureRule& rule,
                                         const Segments& segments) {
  std::vector<double> mx, mw, rx, rw;
  gauss_legendre(rule.polar, &mx, &mw);
  gauss_legendre(rule.radial, &rx, &rw);
  std::vector<LocalPoint> out;
  std::vector<std::pair<double, double>> radii;
  std::vector<RaySegment> pieces;
  const double dphi = 2.0 * M_PI / rule.azimuthal, r_half = 0.5 * r_q;
  for (int a = 0; a < rule.polar; ++a) {
    const double mu = mx[a], st = std::sqrt(std::max(0.0, 1.0 - mu * mu));
    for (int b = 0; b < rule.azimuthal; ++b) {
      const double phi = (b + 0.5) * dphi;
      const Eigen::Vector3d dir(st * std::cos(phi), st * std::sin(phi), mu);
      segments(dir, &pieces);
      radii.clear();
      for (const RaySegment& s : pieces) {
        segment(s.begin, std::min(s.end, r_half), rx, rw, &radii);
        segment(std::max(s.begin, r_half), s.end, rx, rw, &radii);
      }
      for (const auto& [r, w] : radii)
        out.push_back(test_point(centre, r_q, centre + r * dir, mw[a] * dphi * w * r * r));
    }
  }
  return out;
}

}  // namespace

std::vector<LocalPoint> sphere_points(const Eigen::Vector3d& centre, double r_q, const LocalSurface& surface,
                                      const LocalQuadratureRule& rule) {
  return sphere_points_of(centre, r_q, rule, [&](const Eigen::Vector3d& dir, std::vector<RaySegment>* pieces) {
    surface.ray_segments(dir, r_q, pieces);
  });
}

std::vector<LocalPoint> sphere_points(const Eigen::Vector3d& centre, double r_q, const BoxBody& body,
                                      const LocalQuadratureRule& rule) {
  return sphere_points_of(centre, r_q, rule, [&](const Eigen::Vector3d& dir, std::vector<RaySegment>* pieces) {
    pieces->clear();
    const double reach = std::min(r_q, body.exit_distance(centre, dir));
    if (reach > 0.0) pieces->push_back({0.0, reach});
  });
}

std::vector<LocalPoint> triangle_points(const Eigen::Vector3d& centre, double r_q, const Eigen::Vector3d& a,
                                        const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                        const LocalQuadratureRule& rule) {
  std::vector<LocalPoint> out;
  if ((core::closest_point_on_triangle(centre, a, b, c) - centre).norm() >= r_q) return out;
  const SimplexRule tri = triangle_rule(rule.boundary_order);
  const double max_edge = rule.boundary_subdivision * r_q;
  struct Piece {
    Eigen::Vector3d a, b, c;
  };
  std::vector<Piece> stack = {{a, b, c}};
  while (!stack.empty()) {
    const Piece p = stack.back();
    stack.pop_back();
    if ((core::closest_point_on_triangle(centre, p.a, p.b, p.c) - centre).norm() >= r_q) continue;
    const double longest = std::max({(p.b - p.a).norm(), (p.c - p.b).norm(), (p.a - p.c).norm()});
    if (longest > max_edge) {
      const Eigen::Vector3d ab = 0.5 * (p.a + p.b), bc = 0.5 * (p.b + p.c), ca = 0.5 * (p.c + p.a);
      stack.push_back({p.a, ab, ca});
      stack.push_back({ab, p.b, bc});
      stack.push_back({ca, bc, p.c});
      stack.push_back({ab, bc, ca});
      continue;
    }
    const double twice_area = (p.b - p.a).cross(p.c - p.a).norm();
    for (int q = 0; q < tri.size(); ++q) {
      const Eigen::Vector3d x = p.a + tri.points[q].x() * (p.b - p.a) + tri.points[q].y() * (p.c - p.a);
      LocalPoint lp = test_point(centre, r_q, x, tri.weights[q] * twice_area);
      if (!(lp.v > 0.0)) continue;
      lp.dv.setZero();
      out.push_back(lp);
    }
  }
  return out;
}

}  // namespace meshless::lrpim
