#pragma once
// Gauss quadrature over the local sub-domain of one node for the MLPG weak form of the LRPIM model (Atluri &
// Zhu 1998; Liu & Gu 2001): the sphere of radius r_q about the node clipped by the body along rays, and the pieces
// of the body's boundary triangles inside that sphere. No background mesh: every point belongs to one node's test
// function, and only the nodes and the boundary surface are used (docs/LRPIM.md §3).
#include <Eigen/Core>
#include <vector>

#include "meshless/lrpim/box_body.hpp"
#include "meshless/lrpim/surface_body.hpp"

namespace meshless::lrpim {

/// Points of the rules. The sphere rule is a product in spherical coordinates about the node: Gauss-Legendre
/// in cos(theta) (`polar`) x the trapezoid rule in the azimuth (`azimuthal`, exact for trigonometric polynomials)
/// x Gauss-Legendre in r (`radial` per segment). Each ray is integrated over its pieces inside the body (one piece
/// [0, exit] in a convex body, several where a concave body lets the ray leave and re-enter), so the sphere is
/// clipped exactly in r; a piece is split at r_q/2, where the cubic spline test function changes polynomial piece,
/// so the radial integral of a polynomial trial field's stress against grad v is exact. What is not exact is the
/// angular integral over a clipped sphere: the exit distance has kinks in the direction where the ray meets an
/// edge of the body (docs/LRPIM.md §3).
/// The boundary rule: each boundary triangle within r_q of the node is split into four (edge midpoints) until its
/// longest edge is at most boundary_subdivision * r_q, pieces wholly outside the sphere are dropped, and each piece
/// gets the triangle rule of degree boundary_order (meshless/efg/gauss_quadrature_tet.hpp). The test function is C2
/// (zero with its first two derivatives at r_q), so no piece needs to follow the sphere's trace.
struct LocalQuadratureRule {
  int radial = 4;      ///< Gauss points per radial segment (pieces split at r_q/2)
  int polar = 8;       ///< Gauss points in cos(theta)
  int azimuthal = 16;  ///< trapezoid points in the azimuth
  int boundary_order = 4;             ///< degree of the rule on each boundary piece (4: 9 points)
  double boundary_subdivision = 0.25; ///< longest edge of a boundary piece / r_q
};

/// One quadrature point of node i's local domain, with the test function v = w(|X - X_i| / r_q) (the cubic
/// spline of meshless/mls/cubic_spline_weight.hpp, C2, zero on the sphere) and its gradient.
struct LocalPoint {
  Eigen::Vector3d x;       ///< [m]
  double weight = 0.0;     ///< [m^3] (volume) or [m^2] (boundary)
  double v = 0.0;          ///< test function value, dimensionless
  Eigen::Vector3d dv;      ///< grad v [1/m] (volume points; zero on boundary points)
};

/// Gauss-Legendre nodes and weights on [-1, 1], n >= 1 (Newton's iteration on P_n, to round-off).
void gauss_legendre(int n, std::vector<double>* nodes, std::vector<double>* weights);

/// The sphere of radius r_q about the centre of `surface` (a LocalSurface built with radius r_q) clipped by the
/// body: each ray's pieces inside (LocalSurface::ray_segments). Points with zero weight are dropped.
std::vector<LocalPoint> sphere_points(const Eigen::Vector3d& centre, double r_q, const LocalSurface& surface,
                                      const LocalQuadratureRule& rule);

/// The same rule on an axis-aligned box, with the box's analytic exit distance: the reference the surface body's
/// rays are tested against (a box given as triangles must give the same points to round-off).
std::vector<LocalPoint> sphere_points(const Eigen::Vector3d& centre, double r_q, const BoxBody& body,
                                      const LocalQuadratureRule& rule);

/// The part of triangle (a, b, c) inside the sphere of radius r_q about `centre` (the boundary rule above), with
/// v at each point (dv zero). Empty when the triangle does not reach into the sphere.
std::vector<LocalPoint> triangle_points(const Eigen::Vector3d& centre, double r_q, const Eigen::Vector3d& a,
                                        const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                        const LocalQuadratureRule& rule);

}  // namespace meshless::lrpim
