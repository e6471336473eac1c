#pragma once
// Which preconditioner for the Newton systems of the FEM reference: the same assembled tangent solved by
// right-preconditioned GMRES with every candidate Debian's deal.II 9.4 offers (Trilinos ML, PETSc GAMG,
// hypre BoomerAMG, UMFPACK LU), in one run, so the choice in docs/FEM_REFERENCE.md rests on measured ratios.
// deal.II-free header.
#include <mpi.h>

#include <cstddef>
#include <string>
#include <vector>

#include "core/tet_mesh.hpp"
#include "reference_fem/problem.hpp"

namespace reference_fem {

struct PreconditionerTrial {
  std::string name;
  double setup_seconds = 0.0;  ///< building the preconditioner (aggregation, coarse operators; or LU), wall
  double solve_seconds = 0.0;  ///< the GMRES iterations (or the LU triangular solves), wall
  /// The same in CPU time of this process (all its threads): on a shared machine the wall times swell with
  /// the load, the CPU times much less.
  double setup_cpu_seconds = 0.0;
  double solve_cpu_seconds = 0.0;
  int iterations = 0;          ///< GMRES iterations (0 for the direct solve)
  bool converged = false;
  double relative_residual = 0.0;  ///< ||b - A x|| / ||b|| reached
};

struct PreconditionerStudy {
  std::size_t n_dofs = 0;
  double assembly_seconds = 0.0;  ///< the assembly of the system, for scale
  std::vector<PreconditionerTrial> trials;
};

/// The names of the candidates, in the order compare_preconditioners() tries them (for degree 2 meshes).
std::vector<std::string> preconditioner_candidates();

/// Assemble the first Newton system of the step from the undeformed state to `t` on `mesh` (distributed over
/// `communicator`) and solve it with GMRES(60), right-preconditioned, to `tolerance` relative to ||R|| (at most
/// 1000 iterations) with each candidate whose name equals one of `only` (all when empty):
///  * "ML ..."       Trilinos ML smoothed aggregation: rigid-body modes / translations only, and variants;
///  * "GAMG ..."     PETSc GAMG with the rigid-body modes (MatNullSpaceCreateRigidBody);
///  * "BoomerAMG ..." hypre through PETSc: scalar defaults, and the nodal settings for elasticity systems;
///  * "UMFPACK LU"   the direct solve (one process only).
/// Collective.
PreconditionerStudy compare_preconditioners(const core::TetMesh& mesh, const SolverParameters& parameters,
                                            const BoundaryConditions& conditions, double t, double tolerance,
                                            MPI_Comm communicator, const std::vector<std::string>& only = {});

}  // namespace reference_fem
