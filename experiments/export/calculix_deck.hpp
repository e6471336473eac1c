#pragma once
// A case's FEM reference problem at its linear long-time limit as a CalculiX (ccx 2.20) input deck, on the
// second-order mesh core::write_quadratic_mesh wrote (`tissue export`, docs/FEM_REFERENCE.md, "An independent FE
// code: CalculiX").
//
// What the deck states, in SI units (m, N, Pa):
//  * the material: linear isotropic, E = E_inf = K1 K2 / (K1 + K2) and the case's nu: the Kelvin law with k = 0
//    relaxed under a held load (docs/MATERIAL.md §1.1); the case's k is not exported;
//  * the load: the case's full force as a uniform traction force / (the mesh's load-patch area), exactly as
//    core::load_program defines it, applied as the consistent nodal forces of 6-node triangles: the corners get 0
//    and each midside node a third of the face's force (∫ N_i dA of a straight quadratic triangle);
//  * the support (core::FixedRegionSpec): a clamp is *BOUNDARY u = 0 on every node of the fixed faces (what the
//    reference constrains); an elastic support t = -k_s(x) u is the consistent Robin matrix
//    K_ij = ∫ k_s N_i N_j dA over the fixed faces, the same in each direction, represented exactly by springs: a
//    SPRING2 of stiffness -K_ij between every coupled node pair and a grounded SPRING1 of the row sum Σ_j K_ij at
//    every node (together they add exactly K to the stiffness). Some of these stiffnesses are negative (a P2
//    triangle's mass matrix has negative entries); ccx accepts that. The integrals use a 36-point conical Gauss
//    rule per face (exact for polynomials of degree 11 in the face), so k_s's taper is integrated to round-off;
//  * one linear *STATIC step, and the output: *NODE PRINT of U on `sample_node_set` (the .dat the converter reads)
//    and *NODE FILE of U (the .frd, for viewing).
// Thread safety: pure functions.
#include <Eigen/Core>
#include <string>

#include "core/case.hpp"
#include "core/quadratic_mesh_export.hpp"
#include "core/tet_mesh.hpp"

namespace experiments {

/// The set names of an exported mesh that the deck refers to.
struct CalculixSetNames {
  std::string body = "TISSUE";
  std::string support = "SUPPORT";
  std::string sample_nodes = "SAMPLE_CELLS";
};

struct CalculixDeck {
  std::string text;                                   ///< the deck (includes the mesh file)
  Eigen::Vector3d total_load = Eigen::Vector3d::Zero();  ///< [N] sum of the *CLOAD forces
  double load_patch_area = 0.0;                       ///< [m^2]
  Eigen::Vector3d traction = Eigen::Vector3d::Zero(); ///< [Pa]
  double long_time_modulus = 0.0;                     ///< [Pa] E_inf
  int load_nodes = 0;                                 ///< nodes with a *CLOAD
  int pair_springs = 0;                               ///< SPRING2 elements (all three directions)
  int grounded_springs = 0;                           ///< SPRING1 elements (all three directions)
  double support_stiffness_integral = 0.0;            ///< [N/m] ∫ k_s dA over the fixed faces (= Σ_ij K_ij)
};

/// The deck of case `c` on `mesh` (its FEM mesh, as the reference solves it) raised to `quadratic`, whose .inp is
/// `mesh_file` (a path relative to the deck, used in *INCLUDE).
CalculixDeck calculix_deck(const core::Case& c, const core::TetMesh& mesh, const core::QuadraticTetMesh& quadratic,
                           const std::string& mesh_file, const CalculixSetNames& names = {});

}  // namespace experiments
