#include "meshless/efg/gauss_quadrature_tet.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace meshless {

void gauss_legendre_01(int n, std::vector<double>* nodes, std::vector<double>* weights) {
  if (n < 1) throw std::invalid_argument("gauss_legendre_01: n must be >= 1");
  nodes->assign(n, 0.0);
  weights->assign(n, 0.0);
  // Newton on P_n(x) from the Chebyshev-like initial guess; converges in a handful of steps for any n.
  for (int i = 0; i < n; ++i) {
    double x = std::cos(M_PI * (i + 0.75) / (n + 0.5));
    double dp = 1.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = x;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      const double pn = (n == 1) ? x : p1;
      const double pnm1 = (n == 1) ? 1.0 : p0;
      dp = n * (x * pn - pnm1) / (x * x - 1.0);
      const double dx = pn / dp;
      x -= dx;
      if (std::abs(dx) < 1e-16) break;
    }
    // Map [-1, 1] -> [0, 1].
    (*nodes)[i] = 0.5 * (1.0 - x);
    (*weights)[i] = 1.0 / ((1.0 - x * x) * dp * dp);  // 2/((1-x^2) P'^2) times the 1/2 of the map
  }
}

SimplexRule tet_rule(int order) {
  if (order < 1)
    throw std::invalid_argument("tet_rule: quadrature order must be >= 1, got " + std::to_string(order));
  SimplexRule r;
  if (order == 1) {
    r.points = {Eigen::Vector3d::Constant(0.25)};
    r.weights = {1.0 / 6.0};
    r.degree = 1;
    return r;
  }
  if (order == 2) {
    // Symmetric 4-point rule: barycentric (a, b, b, b) and permutations.
    const double a = 0.5854101966249685, b = 0.1381966011250105;
    r.points = {{b, b, b}, {a, b, b}, {b, a, b}, {b, b, a}};
    r.weights.assign(4, 1.0 / 24.0);
    r.degree = 2;
    return r;
  }
  // Collapsed product: xi = u, eta = v (1 - u), zeta = w (1 - u)(1 - v), Jacobian (1 - u)^2 (1 - v). A
  // degree-p polynomial becomes degree <= p + 2 in u, which n-point Gauss integrates exactly when 2n - 1 >= p
  // + 2.
  const int n = (order + 4) / 2;  // ceil((order + 3) / 2)
  std::vector<double> x, w;
  gauss_legendre_01(n, &x, &w);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const double u = x[i], v = x[j], s = x[k];
        r.points.emplace_back(u, v * (1.0 - u), s * (1.0 - u) * (1.0 - v));
        r.weights.push_back(w[i] * w[j] * w[k] * (1.0 - u) * (1.0 - u) * (1.0 - v));
      }
  r.degree = 2 * n - 3;
  return r;
}

SimplexRule triangle_rule(int order) {
  if (order < 1)
    throw std::invalid_argument("triangle_rule: quadrature order must be >= 1, got " + std::to_string(order));
  SimplexRule r;
  if (order == 1) {
    r.points = {{1.0 / 3.0, 1.0 / 3.0, 0.0}};
    r.weights = {0.5};
    r.degree = 1;
    return r;
  }
  if (order == 2) {
    r.points = {{1.0 / 6.0, 1.0 / 6.0, 0.0}, {2.0 / 3.0, 1.0 / 6.0, 0.0}, {1.0 / 6.0, 2.0 / 3.0, 0.0}};
    r.weights.assign(3, 1.0 / 6.0);
    r.degree = 2;
    return r;
  }
  const int n = (order + 3) / 2;  // ceil((order + 2) / 2): Jacobian (1 - u) adds one degree
  std::vector<double> x, w;
  gauss_legendre_01(n, &x, &w);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double u = x[i], v = x[j];
      r.points.emplace_back(u, v * (1.0 - u), 0.0);
      r.weights.push_back(w[i] * w[j] * (1.0 - u));
    }
  r.degree = 2 * n - 2;
  return r;
}

}  // namespace meshless
