#pragma once
// A whole serial mesh -> a parallel::fullydistributed::Triangulation: each MPI process keeps its own part
// (cut by METIS) and one layer of ghost cells, so the FEM's memory per process shrinks with the process
// count. deal.II 9.4 supports simplices in fully distributed triangulations (not in p4est-based ones).
#include <deal.II/distributed/fully_distributed_tria.h>
#include <deal.II/grid/tria.h>

namespace reference_fem {

/// Partition `whole` (the same serial mesh on every process of the target's communicator) into one part per
/// process and build `distributed` from it. Rank 0 partitions and broadcasts the cell owners, so every
/// process builds from the same partition. Coarse cell ids equal the cell indices of `whole` (the core::TetMesh
/// tet index for meshes from build_triangulation()); boundary ids are kept. Collective.
void distribute_triangulation(dealii::Triangulation<3>* whole,
                              dealii::parallel::fullydistributed::Triangulation<3>* distributed);

}  // namespace reference_fem
