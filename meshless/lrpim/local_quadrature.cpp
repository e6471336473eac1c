#include "meshless/lrpim/local_quadrature.hpp"

#include <cmath>
#include <stdexcept>

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

}  // namespace

std::vector<LocalPoint> sphere_points(const Eigen::Vector3d& centre, double r_q, const BoxBody& body,
                                      const LocalQuadratureRule& rule) {
  std::vector<double> mx, mw, rx, rw;
  gauss_legendre(rule.polar, &mx, &mw);
  gauss_legendre(rule.radial, &rx, &rw);
  std::vector<LocalPoint> out;
  std::vector<std::pair<double, double>> radii;
  const double dphi = 2.0 * M_PI / rule.azimuthal;
  for (int a = 0; a < rule.polar; ++a) {
    const double mu = mx[a], st = std::sqrt(std::max(0.0, 1.0 - mu * mu));
    for (int b = 0; b < rule.azimuthal; ++b) {
      const double phi = (b + 0.5) * dphi;
      const Eigen::Vector3d dir(st * std::cos(phi), st * std::sin(phi), mu);
      const double reach = std::min(r_q, body.exit_distance(centre, dir));
      radii.clear();
      segment(0.0, std::min(reach, 0.5 * r_q), rx, rw, &radii);
      segment(0.5 * r_q, reach, rx, rw, &radii);
      for (const auto& [r, w] : radii)
        out.push_back(test_point(centre, r_q, centre + r * dir, mw[a] * dphi * w * r * r));
    }
  }
  return out;
}

std::vector<LocalPoint> face_points(const Eigen::Vector3d& centre, double r_q, const BoxBody& body, int face,
                                    const LocalQuadratureRule& rule) {
  const int ax = BoxBody::axis(face);
  const double delta = std::abs(centre[ax] - body.plane(face));
  std::vector<LocalPoint> out;
  if (delta >= r_q) return out;
  Eigen::Vector3d foot = centre;
  foot[ax] = body.plane(face);
  const double rho_max = std::sqrt(r_q * r_q - delta * delta);
  // The spline's pieces meet at |X - X_i| = r_q / 2, i.e. at rho_k in the plane (when the plane is that close).
  const double rho_k = delta < 0.5 * r_q ? std::sqrt(0.25 * r_q * r_q - delta * delta) : 0.0;
  std::vector<double> rx, rw;
  gauss_legendre(rule.radial, &rx, &rw);
  const Eigen::Vector3d e1 = Eigen::Vector3d::Unit((ax + 1) % 3), e2 = Eigen::Vector3d::Unit((ax + 2) % 3);
  const double dpsi = 2.0 * M_PI / rule.azimuthal;
  std::vector<std::pair<double, double>> radii;
  for (int b = 0; b < rule.azimuthal; ++b) {
    const double psi = (b + 0.5) * dpsi;
    const Eigen::Vector3d dir = std::cos(psi) * e1 + std::sin(psi) * e2;
    const double reach = std::min(rho_max, body.exit_distance_in_face(face, foot, dir));
    radii.clear();
    segment(0.0, std::min(reach, rho_k), rx, rw, &radii);
    segment(rho_k, reach, rx, rw, &radii);
    for (const auto& [rho, w] : radii) {
      LocalPoint p = test_point(centre, r_q, foot + rho * dir, dpsi * w * rho);
      p.dv.setZero();
      out.push_back(p);
    }
  }
  return out;
}

}  // namespace meshless::lrpim
