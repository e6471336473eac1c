#pragma once
// Background Gauss quadrature of the EFG weak form (eq. 19): rules on the reference tetrahedron (volume
// integrals of eq. 21 and the internal force of eq. 24) and on the reference triangle (the penalty
// integral of eq. 23 and the traction integral of eq. 24).
#include <Eigen/Core>
#include <vector>

namespace meshless {

/// A quadrature rule on a reference simplex.
/// Tetrahedron: vertices (0,0,0), (1,0,0), (0,1,0), (0,0,1); weights sum to 1/6.
/// Triangle: vertices (0,0), (1,0), (0,1); weights sum to 1/2 (the third coordinate of `points` is 0).
struct SimplexRule {
  std::vector<Eigen::Vector3d> points;  ///< #q reference coordinates
  std::vector<double> weights;          ///< #q, all > 0
  int degree = 0;                       ///< polynomials up to this total degree are integrated exactly
  int size() const { return static_cast<int>(weights.size()); }
};

/// Gauss-Legendre rule with n points on [0, 1] (weights sum to 1).
void gauss_legendre_01(int n, std::vector<double>* nodes, std::vector<double>* weights);

/// Tetrahedron rule exact for total degree >= `order` (order >= 1):
///   1 -> centroid (1 point), 2 -> symmetric 4-point rule, >= 3 -> collapsed (Duffy / Stroud conical)
///   Gauss-Legendre product with n = ceil((order + 3) / 2) points per direction (n^3 points, all weights >
///   0).
/// MLS shape functions are rational, so no rule integrates eq. 21 exactly; `order` is the knob the patch
/// test reports the integration error against.
SimplexRule tet_rule(int order);

/// Triangle rule exact for total degree >= `order`: 1 -> centroid, 2 -> 3-point, >= 3 -> collapsed
/// Gauss-Legendre with n = ceil((order + 2) / 2) points per direction.
SimplexRule triangle_rule(int order);

}  // namespace meshless
