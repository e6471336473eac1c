#pragma once
// The incision as a ruled surface: a polyline on the tissue surface swept along a depth direction
// (paper §4, Fig. 3, generalised to 3-D). Both the EFG enrichment and the FEM crack use this object.
#include <Eigen/Core>
#include <vector>

#include "core/tet_mesh.hpp"

namespace core {

/// Local coordinates of a point relative to one planar panel of the cut (paper eqs. 29–30 in 3-D).
struct CutCoordinates {
  double s = 0.0;        ///< signed normal distance to the panel plane [m]
  double zeta = 0.0;     ///< coordinate along the incision path, 0 at the panel start [m]
  double depth = 0.0;    ///< coordinate along the depth direction, 0 at the surface line [m]
  double length = 0.0;   ///< panel length along zeta [m]
  int panel = -1;
};

class RuledSurface {
 public:
  /// @param top  polyline points on the tissue surface [m], at least 2
  /// @param direction  unit depth direction;  @param depth  sweep depth [m]
  RuledSurface(std::vector<Eigen::Vector3d> top, const Eigen::Vector3d& direction, double depth);

  const std::vector<Eigen::Vector3d>& top() const { return top_; }
  const Eigen::Vector3d& direction() const { return direction_; }
  double depth() const { return depth_; }
  int num_panels() const { return static_cast<int>(top_.size()) - 1; }

  /// Unit normal of panel i: (segment direction) x (depth direction), orthogonalised.
  Eigen::Vector3d panel_normal(int panel) const;
  /// Coordinates relative to panel i (s, zeta, depth).
  CutCoordinates coordinates(const Eigen::Vector3d& x, int panel) const;
  /// Coordinates relative to the panel whose finite extent is nearest to x.
  CutCoordinates nearest_panel_coordinates(const Eigen::Vector3d& x) const;
  /// Distance from x to the (finite) cut surface [m].
  double distance(const Eigen::Vector3d& x) const;

  /// Triangulation of the cut surface (two triangles per panel), with `extend` [m] added above the
  /// surface line so the cut pierces the tissue surface cleanly.
  void triangulate(PointMatrix* vertices, TriMatrix* triangles, double extend = 0.0) const;
  /// Total area of the cut surface [m^2].
  double area() const;

 private:
  std::vector<Eigen::Vector3d> top_;
  Eigen::Vector3d direction_;
  double depth_;
};

}  // namespace core
