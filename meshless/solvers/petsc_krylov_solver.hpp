#pragma once
// A Krylov solve of the EFG tangent through PETSc (KSP + PC), the method and the preconditioner chosen by a PETSc
// options string: by default LGMRES with SSOR applied through Eisenstat's trick (EfgOptions::krylov_options), or
// algebraic multigrid (PETSc's GAMG, hypre's BoomerAMG, Trilinos ML). The six rigid-body modes of the node cloud
// are the near-null space that multigrid aggregation must reproduce, and the 3 x 3 node blocks are the matrix's
// block size. PETSc stays out of this header.
//
// PETSc (and MPI) must be initialised before the first solver is constructed and finalised after the last
// one is destroyed: dealii::Utilities::MPI::MPI_InitFinalize in main does both. Not thread-safe; the PETSc calls
// themselves run on one thread. A solver destroyed after PETSc was finalised releases nothing (its PETSc objects
// leak) rather than call PETSc and abort.
//
// Processes: with one process in PETSC_COMM_WORLD (or `distributed` false) the solve is serial and references
// the matrix's arrays. Under `mpirun -np P` it is distributed over all P processes, which must construct the same
// solver and call set_matrix() and solve() together (collective). Each owns the rows of a contiguous range of nodes
// (owned_nodes()), copies them into PETSc's distributed matrix, and receives the whole solution. The rows of `a`
// outside that range are never read, so the caller need not assemble them. The SSOR sweeps are then local to
// each process (block Jacobi between them): more iterations, but each process reads only its share of the
// matrix, and the sweeps are bound by memory bandwidth, which each core brings (docs/PERFORMANCE.md, "The
// iterative solve").
#include <Eigen/Core>
#include <memory>
#include <string>
#include <utility>

#include "core/tet_mesh.hpp"
#include "meshless/efg/nodal_sparsity.hpp"

namespace meshless {

/// True once PETSc is initialised in this process (PetscInitialize or MPI_InitFinalize).
bool petsc_initialised();
/// The processes a PetscKrylovSolver constructed now is distributed over: those of PETSC_COMM_WORLD, 1 when PETSc
/// is not initialised.
int petsc_processes();

class PetscKrylovSolver {
 public:
  /// @param nodes #nodes by 3 [m]: unknowns 3i..3i+2 belong to node i; they give the rigid-body modes.
  ///        Copied.
  /// @param petsc_options PETSc options (e.g. "-ksp_type gmres -pc_type gamg"), applied to this solver
  ///        alone (its own options database, not the global one). The defaults are in EfgOptions.
  /// @param relative_tolerance, max_iterations  stopping test of each solve (||r|| <= tol ||b||), set
  ///        before the options string, which may override them.
  /// @param drop_tolerance  > 0: the preconditioner is built from a copy of each matrix without its small
  ///        off-node entries (|a_ij| < drop_tolerance sqrt(|a_ii a_jj|)); the Krylov method applies the matrix
  ///        itself. 0: from the matrix itself. See EfgOptions::preconditioner_drop_tolerance.
  /// Throws std::logic_error when PETSc is not initialised, std::runtime_error when PETSc rejects an option,
  /// std::invalid_argument for a negative drop_tolerance, and for options PETSc's Eisenstat preconditioner cannot
  /// serve: a drop tolerance (its trick applies the preconditioner's matrix as the operator, so a sparser copy would
  /// solve another system) or a relaxation factor other than 1 (PETSc 3.18 crashes in it on this matrix format); and
  /// for a drop tolerance in a distributed solve (the other processes' diagonal entries are not assembled here).
  /// @param distributed  with more than one process in PETSC_COMM_WORLD: distribute the solve over them (below);
  ///        false: solve on this process alone.
  PetscKrylovSolver(const core::PointMatrix& nodes, const std::string& petsc_options, double relative_tolerance,
                    int max_iterations, double drop_tolerance = 0.0, bool distributed = true);
  ~PetscKrylovSolver();
  PetscKrylovSolver(const PetscKrylovSolver&) = delete;
  PetscKrylovSolver& operator=(const PetscKrylovSolver&) = delete;

  /// Use `a` (3N by 3N, compressed, sorted column indices) from now on and build the multigrid hierarchy for
  /// it (or for its sparser copy, with a drop tolerance). The arrays of `a` are referenced, not copied: `a` must
  /// stay alive and unchanged (values, pattern) until the next set_matrix() or the destructor.
  void set_matrix(const SparseMatrix& a);
  /// x with A x = b. Throws std::runtime_error naming PETSc's reason when the stopping test is not met.
  Eigen::VectorXd solve(const Eigen::VectorXd& b);

  int last_iterations() const { return last_iterations_; }
  /// The nodes [first, last) whose rows this process owns: all of them on one process, else [N r / P, N (r + 1) / P)
  /// (integer division) for rank r of P processes and N nodes.
  std::pair<int, int> owned_nodes() const;
  /// Entries of the matrix the preconditioner was built from in the last set_matrix(), over those of `a` (1
  /// without a drop tolerance).
  double preconditioner_fill() const { return preconditioner_fill_; }
  /// Seconds spent building the hierarchy in the last set_matrix().
  double setup_seconds() const { return setup_seconds_; }
  /// Multigrid levels and the operator complexity (sum of the non-zeros of all level operators / those of
  /// A) of the last set-up; 0 when the preconditioner is not PETSc's own multigrid (hypre, ML report
  /// theirs through their own options).
  int levels() const { return levels_; }
  double operator_complexity() const { return operator_complexity_; }
  /// e.g. "GMRES(100) + GAMG (4 levels, operator complexity 1.21)".
  std::string description() const;

 private:
  struct Petsc;
  std::unique_ptr<Petsc> petsc_;
  double drop_tolerance_ = 0.0;
  int last_iterations_ = 0;
  double setup_seconds_ = 0.0;
  double preconditioner_fill_ = 1.0;
  int levels_ = 0;
  double operator_complexity_ = 0.0;
};

}  // namespace meshless
