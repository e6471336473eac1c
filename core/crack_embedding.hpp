#pragma once
// The FEM crack (paper §4, DESIGN.md §2 "FEM crack"): embed the incision's ruled surface in the Gmsh
// OpenCASCADE volume so the tetrahedra conform to it, then duplicate its nodes with Gmsh's Crack plugin.
// deal.II then sees two free faces (FaceTag::crack) where the tissue is cut. Only the FEM mesh is
// cracked; the meshless node cloud stays whole (the EFG model handles the cut by enrichment, eqs. 29–32).
#include <Eigen/Core>
#include <vector>

#include "core/case.hpp"
#include "core/ruled_surface.hpp"
#include "core/tet_mesh.hpp"

namespace core {

/// Physical groups that split_crack_nodes() hands to the Crack plugin.
struct CrackEmbedding {
  int crack_group = 0;          ///< dim 2: the cut surface inside the body
  int open_boundary_group = 0;  ///< dim 1: the cut's curves on the body surface (their nodes are split
                                ///< too, so the cut opens to the outside); the crack front stays shared
  int num_surfaces = 0;
  std::vector<int> front_curves;  ///< the cut's other boundary curves: its front inside the body (a singular line)
};

/// Fragment the body's OCC volumes (one, or several when regions were imprinted) of the current model with
/// the cut (model units = metres / to_m), raised by cut.extension() above its surface line so it pierces the
/// surface cleanly; the parts outside the body are deleted. Throws std::runtime_error when the cut does not
/// end up inside the body.
CrackEmbedding embed_cut_in_body(const std::vector<int>& volume_tags, const RuledSurface& cut, double to_m);

/// Run after the volume mesh is generated: duplicate the nodes on the cut (Gmsh Crack plugin).
void split_crack_nodes(const CrackEmbedding& embedding);

/// Tag the boundary faces lying on the cut surface as FaceTag::crack. Returns how many.
int tag_crack_faces(const RuledSurface& cut, TetMesh* mesh);

/// A cracked box [lo, hi] (metres) meshed at `size` [m]: boundary faces computed, crack faces tagged,
/// every other face free_surface (the caller tags fixed/load faces). For tests of the crack pipeline.
/// When 0 < front_size < size [m], the mesh is refined along the crack's front as the case pipeline refines a
/// cracked FEM mesh (GeometrySpec::crack_front_size; core/gmsh_size_fields.hpp): front_size there, growing to
/// `size` over one `size`.
TetMesh mesh_cracked_block(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const RuledSurface& cut,
                           double size, double front_size = 0.0);

}  // namespace core
