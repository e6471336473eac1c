#pragma once
// The incision as a ruled surface: a polyline on the tissue surface swept along a depth direction (paper §4,
// Fig. 3, generalised to 3-D). This one object is the cut of BOTH models: the FEM reference cracks exactly this
// surface (core/crack_embedding.hpp) and the meshless model enriches its weights with it (meshless/cut/cut_weights.hpp).
//
// Geometry. Every panel contains the depth direction d, so the whole surface projects onto the plane normal to d
// as a 2-D polyline, the TRACE. A point x is described in one global frame built on the trace (CutFrame): the
// signed distance s to the trace (pseudo-normals at the kinks, so s has no jump where panels meet), the arc length
// zeta of the closest trace point, and the depth along d measured from the top line. The cut is the set
// {s = 0, 0 <= zeta <= length, -extension <= depth <= depth()}: the top line is raised by extension() above the
// snapped surface points, so the cut pierces the tissue surface cleanly between the points of the polyline.
//
// The crack FRONT is where the cut ends inside the tissue: its bottom edge (depth = depth()) and its two end edges
// (zeta = 0 and zeta = length). The top edge lies on or above the tissue surface and is not a front. For that
// reason the distances of the frame (distance, beyond_front) treat the cut as open upward: inside the tissue,
// which lies below the top edge, this is the same surface.
//
// Units: metres. Thread safety: every query is const and safe from several threads.
#include <Eigen/Core>
#include <vector>

#include "core/tet_mesh.hpp"

namespace core {

/// Where a point lies relative to the cut, in one global frame (eqs. 29-31 in 3-D). Distances in metres.
///
/// s is the signed distance to the trace EXTENDED by straight rays beyond both ends: a simple infinite curve, so s
/// is continuous everywhere (also around kinks and beyond the ends). distance is the distance to the cut surface
/// itself (open upward): the d of eq. 29. Both are continuous, so the enrichment function phi = s / distance
/// (eq. 31) is continuous everywhere except across the cut. For one straight segment, s is the paper's normal
/// coordinate and distance its d_2, so s / distance is exactly eq. 31's dd_2/ds.
struct CutFrame {
  double s = 0.0;             ///< signed distance to the extended trace, normal to the depth direction; sign = side
  double distance = 0.0;      ///< distance to the cut surface (eq. 29's d); >= |s|
  double beyond_front = 0.0;  ///< sqrt(distance^2 - s^2): how far past the front the point lies (0 behind it)
  bool behind_front = false;  ///< the closest cut point is not on the front: the cut separates the sides here
  double zeta = 0.0;          ///< arc length of the closest point of the extended trace (< 0 or > length beyond the ends)
  double depth = 0.0;         ///< along the depth direction, from the top line (at zeta clamped to the trace)
  Eigen::Vector3d grad_s = Eigen::Vector3d::Zero();         ///< ds/dx [-]
  Eigen::Vector3d grad_distance = Eigen::Vector3d::Zero();  ///< d(distance)/dx [-]; zero where distance = 0
  int segment = 0;            ///< trace segment (panel) nearest to the point
};

/// Panel j of the cut in its own plane: the points origin + a * tangent + z * direction (origin lies in the plane
/// through 0 normal to the direction, so z = x . direction) with 0 <= a <= length and
/// z <= bottom_start + (bottom_end - bottom_start) * a / length: a strip open upward (see RuledSurface).
struct CutPanel {
  Eigen::Vector3d origin, tangent, normal;  ///< normal = tangent x direction, the s > 0 side
  double length = 0.0;                      ///< [m]
  double bottom_start = 0.0, bottom_end = 0.0;  ///< z of the bottom edge at a = 0 and a = length [m]
};

class RuledSurface {
 public:
  /// How far the cut reaches above the surface line, so that it pierces the tissue surface between the snapped
  /// polyline points (where the straight top segments dip below a convex surface). The FEM crack and the meshless
  /// enrichment use the same value.
  static constexpr double kDefaultExtension = 0.003;  ///< [m]

  /// @param top  polyline points on the tissue surface [m], at least 2
  /// @param direction  depth direction (normalised here);  @param depth  sweep depth [m], > 0
  /// @param extension  how far the cut reaches above the top line [m], >= 0
  /// @throws std::invalid_argument naming what is wrong: fewer than 2 points, a non-positive depth, a segment
  ///         parallel to the direction or shorter than 1 micrometre in the trace, a trace that crosses itself, turns
  ///         back on itself (a turn sharper than 160 degrees) or curls across the extension of an end segment
  RuledSurface(std::vector<Eigen::Vector3d> top, const Eigen::Vector3d& direction, double depth,
               double extension = kDefaultExtension);

  const std::vector<Eigen::Vector3d>& top() const { return top_; }
  const Eigen::Vector3d& direction() const { return direction_; }
  double depth() const { return depth_; }
  double extension() const { return extension_; }
  int num_panels() const { return static_cast<int>(top_.size()) - 1; }
  double trace_length() const { return zeta_.back(); }  ///< arc length of the trace [m]

  /// Unit normal of panel i: (segment direction) x (depth direction). The side s > 0 is the side it points to.
  Eigen::Vector3d panel_normal(int panel) const;
  /// Panel i in its own plane (see CutPanel).
  CutPanel panel(int i) const;

  /// The global frame of x (see CutFrame).
  CutFrame frame(const Eigen::Vector3d& x) const;
  /// +1 or -1: the side of the cut x lies on, the sign of s (|s| <= kOnCutTolerance counts as +1). The one rule
  /// both models use to put a point next to the cut on a lip.
  int side(const Eigen::Vector3d& x) const { return frame(x).s >= -kOnCutTolerance ? 1 : -1; }
  /// Points closer than this to the cut's plane are on it [m].
  static constexpr double kOnCutTolerance = 1e-12;
  /// Distance from x to the crack front (the bottom edge and the two end edges, open upward) [m]; its gradient
  /// into *grad when not null (zero on the front itself).
  double front_distance(const Eigen::Vector3d& x, Eigen::Vector3d* grad = nullptr) const;
  /// Distance from x to the finite cut surface, extension included [m].
  double distance(const Eigen::Vector3d& x) const;
  /// True when the segment [a, b] crosses the cut surface (open upward, depth <= depth()). A segment that starts
  /// on the cut surface counts as starting on the s > 0 side.
  bool segment_crosses(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const;

  /// The first `length` [m] of the incision along its trace (progressive cutting): same direction, depth and
  /// extension; the last point is interpolated on its segment. 0 < length <= trace_length().
  RuledSurface truncated(double length) const;

  /// Triangulation of the cut surface (two triangles per panel), from the raised top line down to the bottom.
  void triangulate(PointMatrix* vertices, TriMatrix* triangles) const;
  /// Area of the cut below the top line (extension excluded) [m^2].
  double area() const;

 private:
  Eigen::Vector3d project(const Eigen::Vector3d& x) const { return x - x.dot(direction_) * direction_; }

  std::vector<Eigen::Vector3d> top_;
  Eigen::Vector3d direction_;
  double depth_;
  double extension_;
  // The trace: projected points c_i, unit tangents t_j and normals n_j of its segments, cumulative arc length zeta_i,
  // pseudo-normals m_i at the vertices (mean of the adjacent segment normals), and the top line's height along the
  // direction at each vertex (depth is measured from it, linearly interpolated along each segment).
  std::vector<Eigen::Vector3d> trace_, tangent_, normal_, vertex_normal_;
  std::vector<double> zeta_, top_height_;
};

}  // namespace core
