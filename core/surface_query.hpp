#pragma once
// A closed triangulated surface and the queries the geometry pipeline needs on it: closest point,
// enclosed volume and a watertightness check. Used for the STL input and for the built-in lung's
// fine surface, so that load points, samples and cut points are snapped to the same exact surface
// whatever mesh sizes the two models use.
#include <Eigen/Core>

#include "core/tet_mesh.hpp"

namespace core {

struct SurfacePoint {
  Eigen::Vector3d point;   ///< closest point on the surface [m]
  Eigen::Vector3d normal;  ///< outward unit normal of the triangle it lies on
  double distance = 0.0;   ///< |query - point| [m]
  int triangle = -1;
};

struct TriangleSurface {
  PointMatrix vertices;  ///< #V by 3 [m]
  TriMatrix triangles;   ///< #T by 3, consistently oriented (outward)

  SurfacePoint closest_point(const Eigen::Vector3d& query) const;
  /// Signed enclosed volume by the divergence theorem (positive for outward orientation) [m^3].
  double enclosed_volume() const;
  double area() const;
  /// Number of edges not shared by exactly two triangles (0 for a closed 2-manifold).
  int count_non_manifold_edges() const;
  /// True when x lies inside the closed surface (generalised winding number > 1/2). O(#triangles).
  bool contains(const Eigen::Vector3d& x) const;
  /// Distance [m] along the unit direction `dir` from `origin` to the nearest crossing of the surface with a
  /// positive parameter; infinity when the ray misses it. O(#triangles).
  double ray_hit(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) const;
};

/// Closest point on triangle (a, b, c) to p (Ericson, Real-Time Collision Detection §5.1.5).
Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                          const Eigen::Vector3d& b, const Eigen::Vector3d& c);

}  // namespace core
