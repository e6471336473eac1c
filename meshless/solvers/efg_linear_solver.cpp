#include "meshless/solvers/efg_linear_solver.hpp"

#include <fmt/format.h>

#include <Eigen/IterativeLinearSolvers>
#include <unsupported/Eigen/IterativeSolvers>
#include <Eigen/UmfPackSupport>
#include <chrono>
#include <functional>
#include <stdexcept>
#include <utility>

#include "meshless/solvers/available_memory.hpp"
#include "meshless/solvers/direct_solver_estimate.hpp"

namespace meshless::detail {
class OperatorMatrix;
}  // namespace meshless::detail

// Eigen reads a matrix type's traits when the type is defined (EigenBase): they come first.
namespace Eigen::internal {
template <>
struct traits<meshless::detail::OperatorMatrix> : public traits<Eigen::SparseMatrix<double>> {};
}  // namespace Eigen::internal

namespace meshless::detail {

/// A matrix known only by its product with a vector, in the form Eigen's iterative solvers take (Eigen's
/// "matrix-free solvers" recipe: an EigenBase whose product is implemented below).
class OperatorMatrix : public Eigen::EigenBase<OperatorMatrix> {
 public:
  using Scalar = double;
  using RealScalar = double;
  using StorageIndex = int;
  enum { ColsAtCompileTime = Eigen::Dynamic, MaxColsAtCompileTime = Eigen::Dynamic, IsRowMajor = false };
  OperatorMatrix(const EfgLinearSolver::LinearOperator& apply, Eigen::Index size) : apply_(&apply), size_(size) {}
  Eigen::Index rows() const { return size_; }
  Eigen::Index cols() const { return size_; }
  template <typename Rhs>
  Eigen::Product<OperatorMatrix, Rhs, Eigen::AliasFreeProduct> operator*(const Eigen::MatrixBase<Rhs>& x) const {
    return Eigen::Product<OperatorMatrix, Rhs, Eigen::AliasFreeProduct>(*this, x.derived());
  }
  void apply(const Eigen::VectorXd& x, Eigen::VectorXd* y) const { (*apply_)(x, y); }

 private:
  const EfgLinearSolver::LinearOperator* apply_;
  Eigen::Index size_;
};

}  // namespace meshless::detail

namespace Eigen::internal {

template <typename Rhs>
struct generic_product_impl<meshless::detail::OperatorMatrix, Rhs, SparseShape, DenseShape, GemvProduct>
    : generic_product_impl_base<meshless::detail::OperatorMatrix, Rhs,
                                generic_product_impl<meshless::detail::OperatorMatrix, Rhs>> {
  using Scalar = typename Product<meshless::detail::OperatorMatrix, Rhs>::Scalar;
  template <typename Dest>
  static void scaleAndAddTo(Dest& dst, const meshless::detail::OperatorMatrix& lhs, const Rhs& rhs,
                            const Scalar& alpha) {
    const Eigen::VectorXd x = rhs;
    Eigen::VectorXd y;
    lhs.apply(x, &y);
    dst += alpha * y;
  }
};

}  // namespace Eigen::internal

namespace meshless {

struct EfgLinearSolver::Umfpack {
  // UMFPACK (multifrontal with AMD ordering): the direct solver before MUMPS, kept for comparison (MUMPS factorises the
  // lung's tangent 1.7x faster, meshless/solvers/mumps_lu.hpp). Eigen's SparseLU is an order of magnitude slower still.
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

struct EfgLinearSolver::JacobiBicgstab {
  Eigen::BiCGSTAB<SparseMatrix, Eigen::DiagonalPreconditioner<double>> bicgstab;
};

EfgLinearSolver::EfgLinearSolver(const EfgOptions& options, const NodalSparsity& sparsity,
                                 const core::PointMatrix& nodes, std::string name)
    : options_(options), name_(std::move(name)), kind_(options.linear_solver) {
  if (kind_ == LinearSolverKind::automatic) {
    const DirectSolverEstimate e = estimate_direct_solver_blocked(sparsity.node_pattern(), 3);
    peak_memory_estimate_ = e.peak_memory_bytes;
    flops_estimate_ = e.factorisation_flops;
    available_memory_ = available_memory().bytes;
    kind_ = e.peak_memory_bytes <= options_.direct_solver_memory_fraction * available_memory_ &&
                    (petsc_processes() == 1 || !options_.distributed_krylov_solve)
                ? LinearSolverKind::direct
                : LinearSolverKind::petsc_krylov;
  }
  switch (kind_) {
    case LinearSolverKind::direct:
      // Three unknowns per node, a dense 3 x 3 block per node pair (NodalSparsity): MUMPS orders the node graph.
      mumps_ = std::make_unique<MumpsLu>(name_, options.direct_low_rank_tolerance, options.direct_symmetric_part,
                                         options.direct_node_ordering ? 3 : 1);
      break;
    case LinearSolverKind::direct_umfpack: umfpack_ = std::make_unique<Umfpack>(); break;
    case LinearSolverKind::petsc_krylov:
      if (!petsc_initialised())
        throw std::logic_error(fmt::format(
            "EfgModel '{}': the {} solver needs PETSc, which is not initialised in this program (construct "
            "dealii::Utilities::MPI::MPI_InitFinalize at the start of main)",
            name_,
            options.linear_solver == LinearSolverKind::automatic
                ? fmt::format("PETSc Krylov (chosen because the LU needs an estimated {:.3g} GB of {:.3g} GB "
                              "available)",
                              peak_memory_estimate_ / 1e9, available_memory_ / 1e9)
                : std::string("PETSc Krylov")));
      krylov_ = std::make_unique<PetscKrylovSolver>(nodes, options_.krylov_options, options_.iterative_tolerance,
                                                    options_.iterative_max_iterations,
                                                    options_.preconditioner_drop_tolerance,
                                                    options_.distributed_krylov_solve);
      break;
    case LinearSolverKind::jacobi_bicgstab: jacobi_ = std::make_unique<JacobiBicgstab>(); break;
    case LinearSolverKind::automatic: break;  // resolved above
  }
}

EfgLinearSolver::~EfgLinearSolver() = default;

std::pair<int, int> EfgLinearSolver::nodes_read(int num_nodes) const {
  return krylov_ ? krylov_->owned_nodes() : std::pair<int, int>{0, num_nodes};
}

double EfgLinearSolver::factorisation_flops() const { return mumps_ ? mumps_->factorisation_flops() : 0.0; }

std::string EfgLinearSolver::description() const {
  switch (kind_) {
    case LinearSolverKind::direct:
      return options_.direct_low_rank_tolerance > 0.0
                 ? fmt::format("MUMPS block low-rank LU (METIS ordering of the {} graph, tolerance {:g})",
                               options_.direct_node_ordering ? "node" : "unknowns'", options_.direct_low_rank_tolerance)
                 : fmt::format("MUMPS {} (METIS ordering of the {} graph)",
                               options_.direct_symmetric_part ? "LDL^T of the symmetric part" : "sparse LU",
                               options_.direct_node_ordering ? "node" : "unknowns'");
    case LinearSolverKind::direct_umfpack: return "UMFPACK (Eigen::UmfPackLU)";
    case LinearSolverKind::petsc_krylov: return krylov_->description();
    case LinearSolverKind::jacobi_bicgstab: return "BiCGSTAB (Jacobi preconditioner)";
    case LinearSolverKind::automatic: break;
  }
  return "?";
}

void EfgLinearSolver::prepare(const SparseMatrix& a) {
  prepared_ = false;
  factored_ = false;
  const auto t0 = std::chrono::steady_clock::now();
  switch (kind_) {
    case LinearSolverKind::direct: mumps_->factorise(a); break;
    case LinearSolverKind::direct_umfpack: {
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
      break;
    }
    case LinearSolverKind::petsc_krylov: krylov_->set_matrix(a); break;
    case LinearSolverKind::jacobi_bicgstab: {
      auto& s = jacobi_->bicgstab;
      s.setTolerance(options_.iterative_tolerance);
      s.setMaxIterations(options_.iterative_max_iterations);
      s.compute(a);
      break;
    }
    case LinearSolverKind::automatic: break;
  }
  prepare_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  prepared_ = true;
  factored_ = kind_ == LinearSolverKind::direct || kind_ == LinearSolverKind::direct_umfpack;
}

namespace {

/// Eigen's preconditioner concept around factors computed elsewhere (an earlier tangent's LU): compute() does
/// nothing, solve() is one back-substitution.
class EarlierFactors {
 public:
  template <typename Matrix>
  EarlierFactors& compute(const Matrix&) { return *this; }
  template <typename Matrix>
  EarlierFactors& analyzePattern(const Matrix&) { return *this; }
  template <typename Matrix>
  EarlierFactors& factorize(const Matrix&) { return *this; }
  Eigen::ComputationInfo info() const { return Eigen::Success; }
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const { return back_substitute(b); }
  std::function<Eigen::VectorXd(const Eigen::VectorXd&)> back_substitute;
};

}  // namespace

std::optional<Eigen::VectorXd> EfgLinearSolver::solve_with_earlier_factors(const SparseMatrix& a,
                                                                           const Eigen::VectorXd& rhs,
                                                                           int max_iterations,
                                                                           double tolerance) {
  const LinearOperator product = [&a](const Eigen::VectorXd& x, Eigen::VectorXd* y) { y->noalias() = a * x; };
  return solve_with_earlier_factors(product, rhs, max_iterations, tolerance);
}

std::optional<Eigen::VectorXd> EfgLinearSolver::solve_with_earlier_factors(const LinearOperator& a,
                                                                           const Eigen::VectorXd& rhs,
                                                                           int max_iterations,
                                                                           double tolerance) {
  if (!factored_ || max_iterations <= 0) return std::nullopt;
  const detail::OperatorMatrix matrix(a, rhs.size());
  Eigen::GMRES<detail::OperatorMatrix, EarlierFactors> gmres;
  gmres.preconditioner().back_substitute = [this](const Eigen::VectorXd& b) -> Eigen::VectorXd {
    if (kind_ == LinearSolverKind::direct) return mumps_->solve(b);
    return umfpack_->lu.solve(b);
  };
  gmres.setTolerance(tolerance > 0.0 ? tolerance : options_.iterative_tolerance);
  gmres.setMaxIterations(max_iterations);
  gmres.set_restart(max_iterations);
  gmres.compute(matrix);
  Eigen::VectorXd x = gmres.solve(rhs);
  last_iterations_ = static_cast<int>(gmres.iterations());
  if (gmres.info() != Eigen::Success || !x.allFinite()) return std::nullopt;
  prepared_ = true;
  return x;
}

Eigen::VectorXd EfgLinearSolver::solve(const Eigen::VectorXd& rhs) {
  if (!prepared_) throw std::logic_error("EfgLinearSolver::solve before prepare");
  Eigen::VectorXd x;
  last_iterations_ = 0;
  switch (kind_) {
    case LinearSolverKind::direct: x = mumps_->solve(rhs); break;
    case LinearSolverKind::direct_umfpack: x = umfpack_->lu.solve(rhs); break;
    case LinearSolverKind::petsc_krylov:
      try {
        x = krylov_->solve(rhs);
      } catch (const std::runtime_error& e) {
        throw std::runtime_error(fmt::format("EfgModel '{}': {}", name_, e.what()));
      }
      last_iterations_ = krylov_->last_iterations();
      break;
    case LinearSolverKind::jacobi_bicgstab: {
      auto& s = jacobi_->bicgstab;
      x = s.solve(rhs);
      last_iterations_ = static_cast<int>(s.iterations());
      if (s.info() != Eigen::Success)
        throw std::runtime_error(fmt::format(
            "EfgModel '{}': BiCGSTAB did not converge ({} iterations, error {:.3g}); raise iterative_max_iterations "
            "or use petsc_krylov",
            name_, s.iterations(), s.error()));
      break;
    }
    case LinearSolverKind::automatic: break;
  }
  if (!x.allFinite())
    throw std::runtime_error(fmt::format("EfgModel '{}': the linear solve produced a non-finite update", name_));
  return x;
}

}  // namespace meshless
