#pragma once
// The linear solves of the EFG model: (K_n + K^alpha_n) dU = -R of eq. 20, once per Newton iteration. The
// model assembles the matrix; this class decides how to solve with it (sparse LU or a preconditioned Krylov
// method, options.linear_solver), prepares it once per matrix (factorisation or preconditioner set-up) and
// then solves any number of right-hand sides with it (the model's tangent reuse, docs/MESHLESS.md §2).
#include <Eigen/Core>
#include <memory>
#include <string>

#include "meshless/efg_problem.hpp"
#include "meshless/nodal_sparsity.hpp"

namespace meshless {

class EfgLinearSolver {
 public:
  /// Chooses the method for the matrices of `sparsity` (options.linear_solver; automatic: from the estimated
  /// memory of a sparse LU, meshless/direct_solver_estimate.hpp). `name` labels error messages (the problem).
  /// Neither argument is referenced after construction.
  EfgLinearSolver(const EfgOptions& options, const NodalSparsity& sparsity, std::string name);
  ~EfgLinearSolver();
  EfgLinearSolver(const EfgLinearSolver&) = delete;
  EfgLinearSolver& operator=(const EfgLinearSolver&) = delete;

  /// Factorise `a` (direct) or set up the preconditioner (iterative). `a` is referenced by the iterative
  /// method: it must stay alive and unchanged until the next prepare() or invalidate(). Throws
  /// std::runtime_error with the reason when the factorisation fails (singular matrix, out of memory).
  void prepare(const SparseMatrix& a);
  /// True after prepare() until invalidate(): solve() may be called.
  bool prepared() const { return prepared_; }
  /// The matrix changed: the next solve needs prepare() first.
  void invalidate() { prepared_ = false; }
  /// x with A x = rhs for the prepared A. Throws std::runtime_error when the iterative method does not reach
  /// options.iterative_tolerance within options.iterative_max_iterations, or the result is not finite.
  Eigen::VectorXd solve(const Eigen::VectorXd& rhs);

  bool direct() const { return direct_; }
  /// Krylov iterations of the last solve (0 for the direct solver).
  int last_iterations() const { return last_iterations_; }
  /// The method, for reports ("UMFPACK (Eigen::UmfPackLU)", ...).
  const std::string& description() const { return description_; }
  /// The estimate the automatic choice used [bytes, flops]; 0 when the method was set explicitly.
  double direct_peak_memory_estimate() const { return peak_memory_estimate_; }
  double direct_flops_estimate() const { return flops_estimate_; }

 private:
  struct Umfpack;
  struct Iterative;

  EfgOptions options_;
  std::string name_;
  bool direct_ = true;
  bool prepared_ = false;
  int last_iterations_ = 0;
  std::string description_;
  double peak_memory_estimate_ = 0.0, flops_estimate_ = 0.0;
  std::unique_ptr<Umfpack> umfpack_;
  std::unique_ptr<Iterative> iterative_;
};

}  // namespace meshless
