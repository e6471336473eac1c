#pragma once
// The linear solves of the EFG model: (K_n + K^alpha_n) dU = -R of eq. 20, once per Newton iteration. The
// model assembles the matrix; this class decides how to solve with it (options.linear_solver: MUMPS's sparse
// LU (or UMFPACK's, kept for comparison), a PETSc Krylov method (SSOR by Eisenstat's trick, or algebraic
// multigrid), or Jacobi-BiCGSTAB), prepares it once per matrix (factorisation or preconditioner set-up) and then
// solves any number of right-hand sides with it (the model's tangent reuse, docs/MESHLESS.md §2).
#include <Eigen/Core>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "meshless/solvers/petsc_krylov_solver.hpp"
#include "meshless/efg/efg_problem.hpp"
#include "meshless/solvers/mumps_lu.hpp"
#include "meshless/efg/nodal_sparsity.hpp"

namespace meshless {

class EfgLinearSolver {
 public:
  /// Chooses the method for the matrices of `sparsity` (options.linear_solver; automatic: the direct solver
  /// when the estimated peak memory of its LU (meshless/solvers/direct_solver_estimate.hpp) is below
  /// options.direct_solver_memory_fraction of available_memory(), else petsc_krylov; always petsc_krylov under
  /// mpirun with more than one process and options.distributed_krylov_solve, whose solve is then distributed, where
  /// MUMPS would repeat one factorisation on every process). `nodes` (#nodes by 3, m)
  /// give the rigid-body modes of a multigrid preconditioner. `name` labels error messages (the problem). No
  /// argument is referenced after construction. Throws std::logic_error when petsc_krylov is chosen and PETSc is
  /// not initialised.
  EfgLinearSolver(const EfgOptions& options, const NodalSparsity& sparsity, const core::PointMatrix& nodes,
                  std::string name);
  ~EfgLinearSolver();
  EfgLinearSolver(const EfgLinearSolver&) = delete;
  EfgLinearSolver& operator=(const EfgLinearSolver&) = delete;

  /// Factorise `a` (direct) or set up the preconditioner (iterative). `a` is referenced by the iterative
  /// method: it must stay alive and unchanged until the next prepare() or invalidate(). Throws
  /// std::runtime_error with the reason when the factorisation fails (singular matrix, out of memory).
  void prepare(const SparseMatrix& a);
  /// True after prepare() until invalidate(): solve() may be called.
  bool prepared() const { return prepared_; }
  /// The matrix changed: the next solve needs prepare() first. The factors stay at hand for
  /// solve_with_earlier_factors().
  void invalidate() { prepared_ = false; }
  /// As invalidate(), and the factors may not precondition later matrices either (a failed iterate's, or a body
  /// whose cut changed).
  void forget_factors() { prepared_ = false; factored_ = false; }
  /// dx with A dx = rhs for a newer matrix `a` of the pattern the factors were computed for, by GMRES
  /// preconditioned with those factors (Eigen's GMRES, left-preconditioned), to the relative residual `tolerance`
  /// (≤ 0: options.iterative_tolerance). std::nullopt when there are no factors or GMRES needs more than
  /// max_iterations; the caller then prepares `a`. On success the factors count as prepared again: later
  /// right-hand sides reuse them.
  std::optional<Eigen::VectorXd> solve_with_earlier_factors(const SparseMatrix& a, const Eigen::VectorXd& rhs,
                                                            int max_iterations, double tolerance);
  /// *y = A x for a matrix A that is not assembled (the EFG tangent applied point by point, EfgModel::apply_tangent).
  using LinearOperator = std::function<void(const Eigen::VectorXd& x, Eigen::VectorXd* y)>;
  /// The same for a matrix given by its product with a vector: it must be a matrix of the factors' pattern all the
  /// same (a newer tangent), which the caller assembles and prepares when this returns std::nullopt.
  std::optional<Eigen::VectorXd> solve_with_earlier_factors(const LinearOperator& a, const Eigen::VectorXd& rhs,
                                                            int max_iterations, double tolerance);
  /// True when a direct solver's factors exist, prepared or not: solve_with_earlier_factors() can use them.
  bool has_factors() const { return factored_; }
  /// x with A x = rhs for the prepared A. Throws std::runtime_error when the iterative method does not reach
  /// options.iterative_tolerance within options.iterative_max_iterations, or the result is not finite.
  Eigen::VectorXd solve(const Eigen::VectorXd& rhs);

  /// The method in use: direct, petsc_krylov or jacobi_bicgstab (never automatic).
  LinearSolverKind kind() const { return kind_; }
  /// Krylov iterations of the last solve (0 for the direct solver).
  int last_iterations() const { return last_iterations_; }
  /// The nodes [first, last) whose rows of the matrix prepare() reads: all of them, except for a PETSc Krylov solve
  /// distributed over several MPI processes (meshless/solvers/petsc_krylov_solver.hpp), which reads this process's share.
  std::pair<int, int> nodes_read(int num_nodes) const;
  /// Seconds of the last prepare() (factorisation, or the preconditioner's set-up).
  double prepare_seconds() const { return prepare_seconds_; }
  /// The method, for reports ("MUMPS sparse LU (METIS ordering of the node graph)", "PETSc lgmres + eisenstat", ...).
  std::string description() const;
  /// The estimate and the budget the automatic choice compared [bytes, flops]; 0 when the method was set
  /// explicitly.
  double direct_peak_memory_estimate() const { return peak_memory_estimate_; }
  double direct_flops_estimate() const { return flops_estimate_; }
  /// Floating-point operations of the direct solver's last factorisation (MUMPS RINFOG(3)); 0 for the other methods
  /// and before the first.
  double factorisation_flops() const;
  double available_memory_bytes() const { return available_memory_; }

 private:
  struct Umfpack;
  struct JacobiBicgstab;

  EfgOptions options_;
  std::string name_;
  LinearSolverKind kind_ = LinearSolverKind::direct;
  bool prepared_ = false;
  bool factored_ = false;  // a direct solver's factors exist (of the last prepare()d matrix)
  int last_iterations_ = 0;
  double prepare_seconds_ = 0.0;
  double peak_memory_estimate_ = 0.0, flops_estimate_ = 0.0, available_memory_ = 0.0;
  std::unique_ptr<MumpsLu> mumps_;
  std::unique_ptr<Umfpack> umfpack_;
  std::unique_ptr<PetscKrylovSolver> krylov_;
  std::unique_ptr<JacobiBicgstab> jacobi_;
};

}  // namespace meshless
