#pragma once
// The FEM reference's problem written for another finite-element program (`tissue export`), and that program's
// answer brought back to our samples (`tissue import-ccx`). docs/FEM_REFERENCE.md, "An independent FE code:
// CalculiX".
//
// An export folder holds (units: m, N, Pa):
//   mesh.msh     the FEM mesh (core::build_geometry's fem_mesh, the one the reference solves) raised to straight
//                10-node tets, with physical groups (core/quadratic_mesh_export.hpp)
//   mesh.inp     the same mesh for Abaqus/CalculiX: C3D10 elements, element and node sets
//   job.inp      the CalculiX deck of the linear long-time limit (experiments/export/calculix_deck.hpp)
//   export.json  what the converter needs: each sample's point, element and local coordinates, and the figures of
//                the export (counts, force, areas)
//   case.json    the case as read;  README.md  the units, the sets and the commands
// Sets: TISSUE (all tets), SAMPLE_CELLS (the tets holding a sample), SUPPORT (the fixed region's faces), LOAD (the
// load patch), CRACK_LIP_POSITIVE / CRACK_LIP_NEGATIVE (the cut's faces on each side, s > 0 / s < 0 of
// core::RuledSurface, when the case has a cut), FREE (the rest of the boundary; in the .msh only).
#include <filesystem>
#include <string>

#include "core/case.hpp"
#include "core/geometry.hpp"
#include "experiments/models/model_result.hpp"

namespace experiments {

struct CaseExportSummary {
  int vertices = 0, nodes = 0, tets = 0;  ///< of the linear mesh, of the quadratic one, tets
  int support_faces = 0, load_faces = 0, crack_faces = 0, free_faces = 0, samples = 0, sample_cells = 0;
  double max_sample_offset = 0.0;  ///< [m] the farthest a sample lies outside the faceted mesh
  Eigen::Vector3d total_load = Eigen::Vector3d::Zero();  ///< [N] the deck's *CLOAD sum
  int springs = 0;  ///< support springs in the deck (0 for a clamp)
};

/// Write the export of case `c` (geometry built by core::build_geometry with its FEM mesh) into `folder`, which must
/// exist (the caller stages it: core::OutputDirectory).
CaseExportSummary write_case_export(const core::Case& c, const core::Geometry& geometry,
                                    const std::filesystem::path& folder);

/// The samples of an export folder evaluated from a CalculiX .dat (U printed on at least SAMPLE_CELLS): each sample
/// in its element by the 10-node tet's shape functions (Gmsh's Lagrange basis of mesh.msh's elements). Model
/// "calculix"; displacements in metres. Throws std::runtime_error naming the file and what to do.
ModelResult calculix_samples(const std::filesystem::path& export_folder, const std::filesystem::path& dat_file);

}  // namespace experiments
