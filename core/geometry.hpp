#pragma once
// The geometry pipeline (Gmsh SDK): surface (STL or built-in lung) -> tetrahedral meshes, node cloud,
// fixed region, load patch, sample points and cut surface. Every object is tagged and the same
// Geometry is handed to both models, so they solve the same problem.
#include <Eigen/Core>
#include <optional>
#include <string>

#include "core/case.hpp"
#include "core/ruled_surface.hpp"
#include "core/surface_query.hpp"
#include "core/tet_mesh.hpp"

namespace core {

/// Extra knobs for experiments (e.g. the FEM mesh-convergence study) that override the case.
struct GeometryOptions {
  std::optional<double> fem_mesh_size;  ///< [m] replaces case.geometry.mesh_size for the FEM mesh
  bool build_fem_mesh = true;
  bool build_node_cloud = true;
};

/// Half-width of the band around the load-patch circle, as a fraction of the load radius, where a point-wise
/// comparison is ill-posed: the traction jumps there, so each discretisation's error peaks there. The sample
/// points keep out of it (3 mm for the lung cases' 12 mm patch), and `tissue compare` flags samples inside it by
/// default (a user's samples may still fall there on a surface that curves sharply; docs/EXPERIMENTS.md).
constexpr double kPatchEdgeBandPerLoadRadius = 0.25;

struct Geometry {
  /// Exact reference surface (STL triangles, or the built-in lung's fine surface mesh). Load centre,
  /// samples and cut points are snapped to it, so they do not depend on the mesh sizes.
  TriangleSurface surface;
  double reference_volume = 0.0;  ///< Gmsh OCC mass (built-in) or STL-enclosed volume [m^3]

  TetMesh fem_mesh;       ///< tetrahedra at geometry.mesh_size, tagged faces (FEM reference)
  /// Meshless discretisation: vertices are the EFG node cloud (meshless.node_spacing) and the
  /// tetrahedra are the background integration cells; faces tagged like fem_mesh.
  TetMesh meshless_mesh;

  Eigen::Vector3d load_centre = Eigen::Vector3d::Zero();  ///< snapped load point [m]
  Eigen::Vector3d load_normal = Eigen::Vector3d::UnitZ(); ///< outward surface normal there
  /// #samples by 3 [m], on the surface, clear of the load-patch edge (kPatchEdgeBandPerLoadRadius)
  PointMatrix sample_points;
  std::optional<RuledSurface> cut;                        ///< snapped incision surface
};

/// Build everything a case needs. Throws CaseError for problems the user can fix in the config
/// (empty fixed region, load point or cut away from the body, open STL...).
Geometry build_geometry(const Case& c, const GeometryOptions& options = {});

/// Build the load case's surface only (cheap): used to snap points and to check inputs.
TriangleSurface build_reference_surface(const Case& c, double* reference_volume = nullptr);


}  // namespace core
