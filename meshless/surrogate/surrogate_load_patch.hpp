#pragma once
// The load the surrogate trains with (docs/SURROGATE.md §1): a uniform traction on the boundary faces of ONE
// fixed node cloud around a contact node, so that every contact point and force is solved on the same cloud
// and the same MLS tables (no remeshing, unlike the case's imprinted load ball).
#include <Eigen/Core>
#include <vector>

#include "core/tet_mesh.hpp"
#include "meshless/efg/integration_points.hpp"

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

/// The smooth pressure profile of a training contact: (1 - (r/R)^2)^2 for r < R, 0 beyond. It is C1 at its
/// edge, so as the contact point moves, faces enter and leave the load continuously and the full model's response
/// is a continuous function of the contact point, which a contact region interpolates (docs/SURROGATE.md §1).
double smooth_profile(double distance, double radius);
/// The smooth profile's radius for a patch radius R0: sqrt(3) R0, so that its integral pi R^2 / 3 is the uniform
/// patch's area pi R0^2 and its peak pressure the uniform patch's traction (a smaller profile of the same force
/// concentrates the strain: at R = R0 the lung's 0.4 N tangential training load left the law's range).
inline double smooth_profile_radius(double patch_radius) { return 1.7320508075688772 * patch_radius; }

/// A smooth patch on a fixed cloud: the boundary faces on the contact node's side (normal . n_contact > 0) that
/// hold a point of the model's boundary quadrature within `radius`, and the profile's integral over them in that
/// same quadrature, so that the traction force * profile / integral carries exactly `force` in the model.
struct SmoothLoadPatch {
  std::vector<char> faces;        ///< #boundary faces mask (EfgProblem::loaded_faces)
  double profile_integral = 0.0;  ///< [m^2] sum over the loaded faces' points of w_q * smooth_profile
  int num_faces = 0;
};

/// @param boundary the model's boundary quadrature (boundary_quadrature() of its mesh, order and cut)
/// Throws std::invalid_argument naming the contact point (mm) when no quadrature point lies within `radius`.
SmoothLoadPatch smooth_load_patch(const core::TetMesh& mesh, const QuadraturePoints& boundary,
                                  const Eigen::Vector3d& contact, const Eigen::Vector3d& normal, double radius);

}  // namespace meshless
