#pragma once
// A TetMesh raised to second order (10-node tets, 6-node boundary triangles) and written for other finite-element
// programs through Gmsh: a Gmsh .msh (MSH 4.1) and an Abaqus/CalculiX .inp (C3D10), with named sets.
//
// Why through Gmsh: Gmsh knows both formats and the node orders of their quadratic elements (the .inp's C3D10
// numbers its midside nodes differently from the .msh), so no file format is written by hand here. The midside
// nodes are the edges' midpoints (Mesh.SecondOrderLinear): the elements stay straight-sided, as deal.II's
// FE_SimplexP(2) with its linear mapping treats the same mesh, so the exported mesh is the reference's.
//
// Units: coordinates are written as they are in the TetMesh, in metres.
// Node and element numbers are Gmsh's, the same in both files: Gmsh renumbers both when it raises the order, so
// QuadraticTetMesh maps each TetMesh vertex and tet to its number (vertex_nodes, tet_elements).
// Sets, by name:
//  * every cell set and `body_name` (all tets) are volume physical groups: a .msh physical volume, and in the .inp an
//    *ELSET and an *NSET (the nodes of its elements);
//  * every face set is a .msh physical surface of 6-node triangles, and in the .inp an *NSET of its nodes only:
//    CalculiX refuses elements without a section, so the .inp holds the C3D10 elements alone (Gmsh 4.8 writes a
//    physical surface's triangles as CPS6 elements; the node sets come from physical points on the same nodes).
//
// Thread safety: opens a core::GmshSession, so it must not run while another session is open (Gmsh is a
// process-wide singleton).
#include <Eigen/Core>
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "core/tet_mesh.hpp"

namespace core {

/// A named set of boundary faces (indices into TetMesh::boundary_faces) or of cells (indices into TetMesh::tets).
struct NamedIndexSet {
  std::string name;  ///< upper case, no spaces (an Abaqus set name)
  std::vector<int> indices;
};

struct QuadraticExportSets {
  std::string body_name = "TISSUE";        ///< the set of all tets (its *ELSET carries the section)
  std::vector<NamedIndexSet> face_sets;    ///< disjoint; a face in no set is not written
  std::vector<NamedIndexSet> cell_sets;    ///< any subsets of the tets (they may overlap)
};

using NodeTagMatrix10 = Eigen::Matrix<std::size_t, Eigen::Dynamic, 10, Eigen::RowMajor>;
using NodeTagMatrix6 = Eigen::Matrix<std::size_t, Eigen::Dynamic, 6, Eigen::RowMajor>;

/// The second-order mesh as written to both files.
struct QuadraticTetMesh {
  PointMatrix nodes;      ///< #nodes by 3 [m]; row n is node n + 1
  std::vector<std::size_t> vertex_nodes;  ///< per TetMesh vertex: its node number (0 for a vertex of no tet)
  NodeTagMatrix10 tets;   ///< per TetMesh tet: node tags in Gmsh's order (the 4 corners as in the TetMesh, then the
                          ///< midside nodes of edges 01, 12, 20, 30, 32, 31)
  std::vector<std::size_t> tet_elements;  ///< per TetMesh tet: its element number in both files
  NodeTagMatrix6 faces;   ///< per TetMesh boundary face in a face set: the 3 corners as in the TetMesh, then edges 01,
                          ///< 12, 20 (zeros for a face in no set)
  std::size_t next_element_tag = 1;  ///< the first element tag not used in the .inp (for elements added to it)
  int num_tets() const { return static_cast<int>(tets.rows()); }
  int num_nodes() const { return static_cast<int>(nodes.rows()); }
};

/// Raise `mesh` to second order and write `msh_file` and `inp_file` (either may be empty: not written).
/// Throws std::runtime_error naming the file when Gmsh could not write it, and std::invalid_argument when a set
/// is empty, names an index out of range, or a face lies in two face sets.
QuadraticTetMesh write_quadratic_mesh(const TetMesh& mesh, const QuadraticExportSets& sets,
                                      const std::filesystem::path& msh_file, const std::filesystem::path& inp_file);

}  // namespace core
