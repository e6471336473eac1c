#include "meshless/efg_linear_solver.hpp"

#include <fmt/format.h>

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/UmfPackSupport>
#include <stdexcept>
#include <utility>

#include "meshless/direct_solver_estimate.hpp"

namespace meshless {

struct EfgLinearSolver::Umfpack {
  // UMFPACK (multifrontal, BLAS-3 dense kernels): the EFG rows are dense (hundreds of couplings per
  // row), where Eigen's SparseLU is an order of magnitude slower.
  Eigen::UmfPackLU<UmfpackMatrix> lu;
  /// umfpack_numeric's status. Eigen::UmfPackLU reports every non-zero status as NumericalIssue, but the
  /// determinant under/overflow warnings come with a valid factorisation (UMFPACK user guide), so only the
  /// singular-matrix warning and the errors are failures; the message names which one it was.
  static bool factorised(long status) {
    return status == UMFPACK_OK || status == UMFPACK_WARNING_determinant_underflow ||
           status == UMFPACK_WARNING_determinant_overflow;
  }
  static std::string describe(long status) {
    switch (status) {
      case UMFPACK_WARNING_singular_matrix: return "numerically singular matrix";
      case UMFPACK_ERROR_out_of_memory: return "UMFPACK ran out of memory";
      default: return fmt::format("UMFPACK status {}", status);
    }
  }
  bool analysed = false;
  UmfpackMatrix colmajor;  // UmfPackLU keeps pointers into it: must outlive lu
};

struct EfgLinearSolver::Iterative {
  Eigen::BiCGSTAB<SparseMatrix, Eigen::DiagonalPreconditioner<double>> bicgstab;
};

EfgLinearSolver::EfgLinearSolver(const EfgOptions& options, const NodalSparsity& sparsity, std::string name)
    : options_(options), name_(std::move(name)) {
  switch (options_.linear_solver) {
    case LinearSolverKind::direct: direct_ = true; break;
    case LinearSolverKind::iterative: direct_ = false; break;
    case LinearSolverKind::automatic: {
      const DirectSolverEstimate e = estimate_direct_solver_blocked(sparsity.node_pattern(), 3);
      peak_memory_estimate_ = e.peak_memory_bytes;
      flops_estimate_ = e.factorisation_flops;
      direct_ = e.peak_memory_bytes <= options_.direct_solver_memory_fraction * physical_memory_bytes();
      break;
    }
  }
  description_ = direct_ ? "UMFPACK (Eigen::UmfPackLU)" : "BiCGSTAB (Jacobi preconditioner)";
  if (direct_)
    umfpack_ = std::make_unique<Umfpack>();
  else
    iterative_ = std::make_unique<Iterative>();
}

EfgLinearSolver::~EfgLinearSolver() = default;

void EfgLinearSolver::prepare(const SparseMatrix& a) {
  prepared_ = false;
  if (direct_) {
    Umfpack& f = *umfpack_;
    f.colmajor = a;
    if (!f.analysed) {
      f.lu.analyzePattern(f.colmajor);  // the pattern never changes: order the columns once
      if (f.lu.info() != Eigen::Success)
        throw std::runtime_error(fmt::format("EfgModel '{}': UMFPACK symbolic analysis failed: {}", name_,
                                             Umfpack::describe(f.lu.umfpackFactorizeReturncode())));
      f.analysed = true;
    }
    f.lu.factorize(f.colmajor);
    const long status = f.lu.umfpackFactorizeReturncode();
    if (!Umfpack::factorised(status))
      throw std::runtime_error(
          fmt::format("EfgModel '{}': sparse LU factorisation failed: {}", name_, Umfpack::describe(status)));
  } else {
    Eigen::BiCGSTAB<SparseMatrix, Eigen::DiagonalPreconditioner<double>>& s = iterative_->bicgstab;
    s.setTolerance(options_.iterative_tolerance);
    s.setMaxIterations(options_.iterative_max_iterations);
    s.compute(a);
  }
  prepared_ = true;
}

Eigen::VectorXd EfgLinearSolver::solve(const Eigen::VectorXd& rhs) {
  if (!prepared_) throw std::logic_error("EfgLinearSolver::solve before prepare");
  Eigen::VectorXd x;
  if (direct_) {
    x = umfpack_->lu.solve(rhs);
    last_iterations_ = 0;
  } else {
    auto& s = iterative_->bicgstab;
    x = s.solve(rhs);
    last_iterations_ = static_cast<int>(s.iterations());
    if (s.info() != Eigen::Success)
      throw std::runtime_error(fmt::format("EfgModel '{}': BiCGSTAB did not converge ({} iterations, error {:.3g})",
                                           name_, s.iterations(), s.error()));
  }
  if (!x.allFinite())
    throw std::runtime_error(fmt::format("EfgModel '{}': the linear solve produced a non-finite update", name_));
  return x;
}

}  // namespace meshless
