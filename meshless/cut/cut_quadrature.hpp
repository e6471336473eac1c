#pragma once
// Background cells and boundary faces that a cut crosses (paper §4): so that no Gauss point integrates across the
// discontinuity of the cut shape functions, a cell or face that a panel of the cut crosses is split along that
// panel's plane (every crossing panel in turn, in panel order) and each piece gets its own Gauss rule. Within a piece
// the shape functions are smooth. The pieces of the cut inside each cell also give the lips' boundary points.
//
// A panel crosses a cell when the cell has vertices strictly on both sides of the panel's plane and their
// intersection polygon overlaps the panel (clipped to the panel's strip, core::CutPanel). A vertex within
// core::RuledSurface::kOnCutTolerance of the plane counts as lying on its s > 0 side (the rule the weights use for
// nodes on the cut), so a cell face that lies in the plane is counted once, by the cell on the s < 0 side.
//
// Units: metres. All functions are pure and thread-safe.
#include <Eigen/Core>
#include <array>
#include <vector>

#include "core/ruled_surface.hpp"

namespace meshless {

using TetVertices = std::array<Eigen::Vector3d, 4>;
using TriangleVertices = std::array<Eigen::Vector3d, 3>;

/// The panels of `cut` that cross the tetrahedron, ascending. When `lips` is not null it receives, per crossing
/// panel, the part of the cut inside the tetrahedron: a convex polygon (3-D points, in order around it).
std::vector<int> panels_crossing_tet(const core::RuledSurface& cut, const TetVertices& tet,
                                     std::vector<std::vector<Eigen::Vector3d>>* lips = nullptr);

/// The panels of `cut` that cross the triangle (a boundary face), ascending.
std::vector<int> panels_crossing_triangle(const core::RuledSurface& cut, const TriangleVertices& triangle);

/// The tetrahedron split by the planes of `panels` (in that order). Pieces of zero volume (a plane through a vertex
/// or an edge) are dropped; the pieces fill the tetrahedron exactly.
std::vector<TetVertices> split_tet(const core::RuledSurface& cut, const std::vector<int>& panels, const TetVertices& tet);

/// The triangle split by the planes of `panels` (in that order); zero-area pieces dropped.
std::vector<TriangleVertices> split_triangle(const core::RuledSurface& cut, const std::vector<int>& panels,
                                             const TriangleVertices& triangle);

double tet_volume(const TetVertices& tet);           ///< unsigned [m^3]
double triangle_area(const TriangleVertices& tri);   ///< [m^2]

}  // namespace meshless
