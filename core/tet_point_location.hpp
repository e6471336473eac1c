#pragma once
// Where points lie in a TetMesh: the containing tet and the point's barycentric coordinates, for evaluating any
// field on the mesh (a second-order field of another FE program, tissue import-ccx) without deal.II.
//
// The rule is the FEM reference's (reference_fem/sample_evaluator.hpp), so both evaluate a sample in the same
// place: a point inside the mesh is in the tet that contains it; a point a hair outside the faceted mesh (the
// samples lie on the exact, curved surface) is projected into the nearest tet by clamping its barycentric
// coordinates to >= 0; behind a crack's front a point belongs to the lip core::RuledSurface::side gives it, in a
// tet with no vertex on the other side.
//
// Cost: a linear scan over the tets per point (a few ms per point on the lung meshes); for tens to hundreds of
// sample points, not for millions. Thread safety: a pure function.
#include <Eigen/Core>
#include <vector>

#include "core/ruled_surface.hpp"
#include "core/tet_mesh.hpp"

namespace core {

struct TetPointLocation {
  int tet = -1;                                       ///< index into TetMesh::tets
  Eigen::Vector4d barycentric = Eigen::Vector4d::Zero();  ///< of the tet's 4 vertices in TetMesh order, sum 1, >= 0
  double offset = 0.0;  ///< [m] distance from the point to where it is evaluated (0 inside the mesh)
};

/// Locate every row of `points` [m]. Throws std::runtime_error naming the point when it lies farther than
/// `tolerance` [m] outside the mesh (on its lip, when `cut` is given).
std::vector<TetPointLocation> locate_points(const TetMesh& mesh, const PointMatrix& points, double tolerance,
                                            const RuledSurface* cut = nullptr);

}  // namespace core
