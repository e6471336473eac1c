#pragma once
// The load the surrogate trains with (docs/SURROGATE.md §1): a uniform traction on the boundary faces of ONE
// fixed node cloud around a contact node, so that every contact point and force is solved on the same cloud
// and the same MLS tables (no remeshing, unlike the case's imprinted load ball).
#include <Eigen/Core>
#include <vector>

#include "core/tet_mesh.hpp"

namespace meshless {

/// The surface nodes of a node cloud: the vertices of its boundary faces, where the surrogate reports
/// displacements (paper eq. 28: "every other node" of the surface).
struct SurfaceNodes {
  std::vector<int> vertex;     ///< #S mesh vertex ids, increasing
  core::PointMatrix position;  ///< #S by 3 [m]
  core::PointMatrix normal;    ///< #S by 3 outward unit normals (area-weighted mean of the incident faces)

  int size() const { return static_cast<int>(vertex.size()); }
  /// Index (into vertex/position) of the surface node nearest x, and its distance [m].
  int nearest(const Eigen::Vector3d& x, double* distance = nullptr) const;
};

/// Surface nodes of `mesh` (boundary faces must be oriented outward, as core::TetMesh guarantees).
SurfaceNodes surface_nodes(const core::TetMesh& mesh);

/// A traction patch on a fixed cloud: the boundary faces whose centroid lies within `radius` of the contact
/// node and whose outward normal points to the same side as the node's (normal . n_contact > 0), the same
/// side rule as the case's load patch (core/geometry.cpp). The patch's edge follows the faces, so it is
/// ragged at the node spacing; the traction is force / area, so the total force is exact.
struct LoadPatch {
  std::vector<char> faces;  ///< #boundary faces mask (EfgProblem::loaded_faces)
  double area = 0.0;        ///< [m^2]
  int num_faces = 0;
};

/// @param mesh the node cloud (its boundary faces)
/// @param contact contact node position [m], normal (unit)
/// @param radius patch radius [m]
/// Throws std::invalid_argument naming the contact point (mm) when no face qualifies.
LoadPatch load_patch(const core::TetMesh& mesh, const Eigen::Vector3d& contact, const Eigen::Vector3d& normal,
                     double radius);

}  // namespace meshless
