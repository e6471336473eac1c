#pragma once
// Numbering a tet mesh so that what is close in space is close in memory.
//
// Gmsh's numbering of a volume mesh leaves neighbouring vertices and tetrahedra far apart in the arrays. The EFG
// model's assembly visits, for every node, every integration point of its support and reads that point's whole
// shape-function row (docs/MESHLESS.md §4, "Assembly"): with Gmsh's numbering consecutive nodes share few points,
// and the rows are read from memory again and again. Numbered by reverse Cuthill–McKee (Boost.Graph), with the
// tetrahedra (hence the integration points, made cell by cell) sorted by their vertices, consecutive nodes share
// most of their points, and those rows stay in cache: one lung_small tangent took 5.80 s before and 3.47 s after
// on one core. The FEM mesh is numbered the same way: deal.II numbers the degrees of freedom cell by cell.
//
// The renumbering is a permutation: the mesh is the same set of vertices, tetrahedra and tagged faces.
#include <vector>

#include "core/tet_mesh.hpp"

namespace core {

/// Renumber `mesh` in place: vertices by reverse Cuthill–McKee on the vertex graph of the tetrahedra (each
/// connected component from a pseudo-peripheral vertex), then tetrahedra and boundary faces sorted by their
/// smallest new vertex number (ties by the next ones). Orientation, tags and `vertex_fixed` follow their entities.
/// @return #V: the new number of each old vertex (new_index[old] = new)
std::vector<int> order_for_locality(TetMesh* mesh);

}  // namespace core
