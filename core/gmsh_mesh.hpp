#pragma once
// Reading the current Gmsh mesh into the project's types (metres): the triangles of all surfaces as a
// TriangleSurface, and the linear tetrahedra as a TetMesh with positive tets and outward boundary faces.
// Shared by the geometry pipeline and the cracked-block test mesh.
#include "core/surface_query.hpp"
#include "core/tet_mesh.hpp"

namespace core {

/// All triangles of the current Gmsh mesh, model units scaled by `to_m` to metres (orientation as in Gmsh).
TriangleSurface read_gmsh_triangles(double to_m);

/// All linear tetrahedra of the current Gmsh mesh in metres, made positive, with the boundary faces (faces
/// of exactly one tet; after the Crack plugin, both lips of a cut) oriented outward and tagged free_surface.
TetMesh read_gmsh_tets(double to_m);

/// Orient tets positively and collect the boundary faces (faces used by exactly one tet), outward; every
/// face is tagged free_surface and no vertex is fixed.
void finish_topology(TetMesh* mesh);

}  // namespace core
