#pragma once
// core::TetMesh -> deal.II simplex Triangulation<3>, so the FEM reference solves on exactly the Gmsh
// tetrahedra and boundary tags that core::Geometry hands to both models.
#include <deal.II/grid/tria.h>

#include "core/tet_mesh.hpp"

namespace reference_fem {

/// Fill `triangulation` (must be empty) with one simplex cell per tet. Boundary faces get the
/// core::FaceTag value as boundary id (free 0, fixed 1, load 2, crack 3). Crack faces are ordinary
/// boundary faces because their nodes are duplicated in the mesh (core/crack_embedding.hpp).
void build_triangulation(const core::TetMesh& mesh, dealii::Triangulation<3>* triangulation);

}  // namespace reference_fem
