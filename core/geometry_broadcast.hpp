#pragma once
// The geometry of a distributed run (the FEM reference, or the EFG model with its Krylov solve distributed) is
// built once, by rank 0, and sent to the other MPI processes.
// Why not on every process (Gmsh with one thread is deterministic): meshing holds the OCC model, the
// reference surface and Gmsh's own mesh, several times the memory of the TetMesh that is sent, and N
// processes per node would hold N copies at once; one build also cannot depend on how Gmsh behaves on
// different cluster nodes. The other processes wait meanwhile, as they would have been meshing anyway.
// Plain MPI (no deal.II): it serves both models, so it lives in core.
#include <mpi.h>

#include <functional>

#include "core/geometry.hpp"

namespace core {

/// Run `build` on rank 0 only and give every process of `communicator` the parts the models read:
/// fem_mesh, meshless_mesh, sample_points, load_centre, load_normal, reference_volume and the cut (the reference
/// surface stays on rank 0). When `build` throws on rank 0, every process throws the same
/// error (a core::CaseError stays a CaseError with its file and JSON path), so all of them stop together.
/// Collective.
core::Geometry build_on_rank_zero(const std::function<core::Geometry()>& build, MPI_Comm communicator);

}  // namespace core
