#pragma once
// The body of the LRPIM model given by its closed boundary surface only (no background mesh, which is the point of
// LRPIM): the triangles of a load case's node cloud (core::Geometry::meshless_mesh's boundary faces, whose
// vertices are nodes) or of a box. Each node's local sub-domain is the sphere of radius r_q clipped by the body
// along rays from the node (meshless/lrpim/local_quadrature.hpp), so the body answers two questions:
//   * which parts of a ray from a node lie inside the body within r_q (ray_segments: every crossing with the
//     surface, sorted, in or out by the sign of d.n, so concave parts and re-entering rays are handled), and
//   * which boundary triangles lie within r_q of the node (triangles_near), for the boundary integrals.
// docs/LRPIM.md §3.
//
// Units: metres. Lifetime: the body owns copies of its arrays; its triangle index lives behind a shared pointer,
// so copies and moves are cheap and share it. Thread safety: every const method may run from several threads.
#include <Eigen/Core>
#include <memory>
#include <vector>

#include "core/tet_mesh.hpp"
#include "meshless/lrpim/box_body.hpp"

namespace meshless::lrpim {

/// One piece [begin, end] of a ray inside the body, distances from the ray's origin [m].
struct RaySegment {
  double begin = 0.0, end = 0.0;
};

class SurfaceBody {
 public:
  /// @param vertices #V by 3 [m]
  /// @param triangles #T by 3 vertex ids; a closed surface, oriented with outward normals (right-hand rule)
  /// @param labels #T, >= 0: the caller's boundary-condition id of each triangle (LrpimProblem::conditions)
  /// @throws std::invalid_argument for mismatched sizes, ids out of range, a negative label or a zero-area
  ///   triangle (naming the triangle)
  SurfaceBody(core::PointMatrix vertices, core::TriMatrix triangles, std::vector<int> labels);

  /// The axis-aligned box as 12 triangles; triangle labels are the BoxBody face indices 0..5 (-x +x -y +y -z +z).
  static SurfaceBody from_box(const BoxBody& box);
  /// The boundary faces of `mesh` (outward, as core::TetMesh keeps them), labelled by int(FaceTag). Only the
  /// vertices the faces use are kept (renumbered); the tets are not read.
  static SurfaceBody from_mesh_boundary(const core::TetMesh& mesh);

  int num_triangles() const { return static_cast<int>(triangles_.rows()); }
  int label(int t) const { return labels_[t]; }
  Eigen::Vector3d corner(int t, int k) const { return vertices_.row(triangles_(t, k)).transpose(); }
  const Eigen::Vector3d& normal(int t) const { return normals_[t]; }  ///< outward unit normal
  double area(int t) const { return areas_[t]; }                       ///< [m^2]
  double labelled_area(int label) const;                               ///< [m^2]
  const core::PointMatrix& vertices() const { return vertices_; }
  const core::TriMatrix& triangles() const { return triangles_; }

  /// The triangles whose closest point to x is closer than `radius` [m] (unordered; `out` is cleared first).
  void triangles_near(const Eigen::Vector3d& x, double radius, std::vector<int>* out) const;

  /// Distance from x to the closest point of the surface [m] (through the triangle index: O(log T) when the
  /// surface is within `search_radius`; infinity when no triangle is that close).
  double distance_to_surface(const Eigen::Vector3d& x, double search_radius) const;

 private:
  struct Index;
  core::PointMatrix vertices_;
  core::TriMatrix triangles_;
  std::vector<int> labels_;
  std::vector<Eigen::Vector3d> normals_;
  std::vector<double> areas_;
  std::shared_ptr<const Index> index_;
};

/// The surface around one point x inside or on the body, as the rays of x's local sphere see it: the triangles
/// within `radius` of x, and among them those that touch x (closer than `tolerance`: x is a surface node, or lies
/// on a triangle's edge or face). Built once per node and reused by all its rays.
/// Lifetime: references `body`, which must outlive it. Thread safety: const methods may run concurrently.
class LocalSurface {
 public:
  /// @param radius the local sphere's radius r_q [m]
  /// @param tolerance distance under which x counts as on a triangle [m] (e.g. 1e-9 of the node spacing)
  LocalSurface(const SurfaceBody& body, const Eigen::Vector3d& x, double radius, double tolerance);

  bool on_surface() const { return !touching_.empty(); }
  const std::vector<int>& triangles() const { return near_; }  ///< within radius, touching ones included, ascending
  const std::vector<int>& touching() const { return touching_; }  ///< those closer to x than the tolerance

  /// The pieces of the ray x + r d (d a unit vector), 0 <= r <= r_max <= radius, that lie inside the body,
  /// ascending. Crossings are every ray-triangle intersection (Moller & Trumbore 1997) with the nearby triangles,
  /// sorted by distance; a crossing leaves the body when d.n > 0 and enters it when d.n < 0. Crossings at one
  /// distance (a ray through an edge or a vertex meets several triangles) count once, and a group of both signs
  /// (the ray grazes a ridge) changes nothing. The state at r = 0 is "inside" for a point off the surface
  /// (nodes lie in the body); on the surface it is decided by the touching triangles alone: seen from x + eps d,
  /// they subtend the solid angle 4 pi (1 - a) inside the body and -4 pi a outside it (a = the body's solid-angle
  /// fraction at x, 0 < a < 1), so the sign of their solid angle says whether d points into the body. A ray
  /// leaving the body through the surface point it starts from therefore has no segment (length 0).
  void ray_segments(const Eigen::Vector3d& d, double r_max, std::vector<RaySegment>* out) const;

 private:
  const SurfaceBody* body_;
  Eigen::Vector3d x_;
  double radius_;
  std::vector<int> near_, touching_, crossing_;  // crossing_: near_ without touching_
};

/// Signed solid angle [sr] of triangle (a, b, c) seen from p: positive when p lies on the side its (right-hand)
/// normal points away from, i.e. inside a closed outward surface (Van Oosterom & Strackee 1983, as in
/// core::TriangleSurface::contains).
double triangle_solid_angle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                            const Eigen::Vector3d& c);

}  // namespace meshless::lrpim
