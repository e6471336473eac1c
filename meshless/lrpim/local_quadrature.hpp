#pragma once
// Gauss quadrature over the local sub-domain of one node for the MLPG weak form of the LRPIM model (Atluri &
// Zhu 1998; Liu & Gu 2001): the sphere of radius r_q about the node clipped by the body, and the discs where that
// sphere meets the body's boundary planes. No background mesh: every point belongs to one node's test function.
#include <Eigen/Core>
#include <vector>

#include "meshless/lrpim/box_body.hpp"

namespace meshless::lrpim {

/// Points of the rules. The sphere rule is a product in spherical coordinates about the node: Gauss-Legendre
/// in cos(theta) (`polar`) x the trapezoid rule in the azimuth (`azimuthal`, exact for trigonometric polynomials)
/// x Gauss-Legendre in r (`radial` per segment). Each ray stops where it leaves the body, so a convex body
/// (star-shaped about the node suffices) clips the sphere exactly in r; the radial range is split at r_q/2, where
/// the cubic spline test function changes polynomial piece, so the radial integral of a polynomial trial field's
/// stress against grad v is exact. What is not exact is the angular integral over a clipped sphere: the exit
/// distance has kinks in the direction where the ray meets an edge of the body (docs/LRPIM.md §3).
struct LocalQuadratureRule {
  int radial = 4;      ///< Gauss points per radial segment (two segments: [0, r_q/2] and [r_q/2, exit])
  int polar = 8;       ///< Gauss points in cos(theta)
  int azimuthal = 16;  ///< trapezoid points in the azimuth (also the angular points on the boundary discs)
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

/// The sphere of radius r_q about `centre` clipped by the body; points with zero weight are dropped.
std::vector<LocalPoint> sphere_points(const Eigen::Vector3d& centre, double r_q, const BoxBody& body,
                                      const LocalQuadratureRule& rule);

/// The disc where that sphere meets the plane of `face`, clipped by the face (polar rule about the projection
/// of the centre onto the plane). Empty when the sphere does not reach the plane.
std::vector<LocalPoint> face_points(const Eigen::Vector3d& centre, double r_q, const BoxBody& body, int face,
                                    const LocalQuadratureRule& rule);

}  // namespace meshless::lrpim
