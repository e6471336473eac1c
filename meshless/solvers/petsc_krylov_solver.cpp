#include "meshless/solvers/petsc_krylov_solver.hpp"

#include <fmt/format.h>
#include <petscksp.h>

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <type_traits>
#include <vector>

namespace meshless {

static_assert(std::is_same_v<PetscInt, SparseMatrix::StorageIndex>,
              "PETSc must use the index type of meshless::SparseMatrix to reference its arrays without a copy");
static_assert(std::is_same_v<PetscScalar, double>, "PETSc must be built with real double scalars");

namespace {

/// Throws std::runtime_error with PETSc's own text for a non-zero error code.
void check(PetscErrorCode code, const char* call) {
  if (code == 0) return;
  const char* text = nullptr;
  PetscErrorMessage(code, &text, nullptr);
  throw std::runtime_error(fmt::format("PETSc: {} failed: {} (error {})", call, text ? text : "unknown", code));
}

/// Makes a solver's own options database PETSc's default while it lives. PETSc reads the options of the objects
/// it creates inside a preconditioner (the multigrid levels' smoothers, "-mg_levels_...") from the default
/// database, not from the parent's: without this they would silently ignore the options string.
class DefaultOptionsWhileAlive {
 public:
  explicit DefaultOptionsWhileAlive(PetscOptions options) { check(PetscOptionsPush(options), "PetscOptionsPush"); }
  ~DefaultOptionsWhileAlive() { PetscOptionsPop(); }
  DefaultOptionsWhileAlive(const DefaultOptionsWhileAlive&) = delete;
  DefaultOptionsWhileAlive& operator=(const DefaultOptionsWhileAlive&) = delete;
};

}  // namespace

bool petsc_initialised() { return PetscInitializeCalled == PETSC_TRUE && PetscFinalizeCalled == PETSC_FALSE; }

int petsc_processes() {
  int processes = 1;
  if (petsc_initialised()) MPI_Comm_size(PETSC_COMM_WORLD, &processes);
  return processes;
}

struct PetscKrylovSolver::Petsc {
  PetscOptions options = nullptr;
  KSP ksp = nullptr;
  Mat a = nullptr;
  Mat p = nullptr;        // the preconditioner's matrix when a drop tolerance is set (else a)
  SparseMatrix sparser;   // its entries, referenced by p
  MatNullSpace rigid_body_modes = nullptr;
  Vec coordinates = nullptr, b = nullptr, x = nullptr;
  PetscInt n = 0;
  // The processes share the rows node by node: this process owns rows [first_row, first_row + local_rows) of
  // every matrix and vector; row_counts/row_offsets hold every process's share (for gathering the solution).
  MPI_Comm comm = PETSC_COMM_SELF;
  PetscInt first_row = 0, local_rows = 0;
  std::vector<int> row_counts, row_offsets;

  /// A PETSc matrix of `a`'s owned rows: its arrays referenced on one process, copied when distributed.
  Mat matrix(const SparseMatrix& a);

  ~Petsc() {
    // Destruction must not throw; PETSc reports its own errors here. After PetscFinalize (an object that
    // outlived MPI_InitFinalize) PETSc and MPI may not be called: leak rather than abort the program.
    if (!petsc_initialised()) return;
    if (ksp) KSPDestroy(&ksp);
    if (rigid_body_modes) MatNullSpaceDestroy(&rigid_body_modes);
    if (a) MatDestroy(&a);
    if (p) MatDestroy(&p);
    if (coordinates) VecDestroy(&coordinates);
    if (b) VecDestroy(&b);
    if (x) VecDestroy(&x);
    if (options) PetscOptionsDestroy(&options);
  }
};

PetscKrylovSolver::PetscKrylovSolver(const core::PointMatrix& nodes, const std::string& petsc_options,
                                     double relative_tolerance, int max_iterations, double drop_tolerance,
                                     bool distributed)
    : petsc_(std::make_unique<Petsc>()), drop_tolerance_(drop_tolerance) {
  if (!(drop_tolerance >= 0.0))
    throw std::invalid_argument(
        fmt::format("PetscKrylovSolver: the drop tolerance must be >= 0 (0: none), got {}", drop_tolerance));
  if (!petsc_initialised())
    throw std::logic_error(
        "PetscKrylovSolver: PETSc is not initialised; construct dealii::Utilities::MPI::MPI_InitFinalize (or call "
        "PetscInitialize) at the start of main");
  Petsc& p = *petsc_;
  p.n = static_cast<PetscInt>(3 * nodes.rows());
  const int processes = distributed ? petsc_processes() : 1;
  int rank = 0;
  if (processes > 1) MPI_Comm_rank(PETSC_COMM_WORLD, &rank);
  p.comm = processes > 1 ? PETSC_COMM_WORLD : PETSC_COMM_SELF;
  // Whole nodes per process, as even as the count allows (a node's three rows stay together: the block size).
  for (int r = 0; r <= processes; ++r)
    p.row_offsets.push_back(static_cast<int>(3 * (nodes.rows() * r / processes)));
  for (int r = 0; r < processes; ++r) p.row_counts.push_back(p.row_offsets[r + 1] - p.row_offsets[r]);
  p.first_row = p.row_offsets[rank];
  p.local_rows = p.row_counts[rank];
  if (processes > 1 && drop_tolerance > 0.0)
    throw std::invalid_argument(fmt::format(
        "PetscKrylovSolver: a drop tolerance ({:g}, EfgOptions::preconditioner_drop_tolerance) compares each entry "
        "with the diagonal of both its rows, but a solve distributed over {} processes has only this process's rows "
        "assembled: set it to 0, or solve on each process alone (EfgOptions::distributed_krylov_solve = false)",
        drop_tolerance, processes));
  check(PetscOptionsCreate(&p.options), "PetscOptionsCreate");
  check(PetscOptionsInsertString(p.options, petsc_options.c_str()), "PetscOptionsInsertString");

  // The rigid-body modes from the node positions, centred (PETSc orthonormalises them).
  check(VecCreateMPI(p.comm, p.local_rows, p.n, &p.coordinates), "VecCreateMPI");
  check(VecSetBlockSize(p.coordinates, 3), "VecSetBlockSize");
  {
    const Eigen::RowVector3d centre = nodes.colwise().mean();
    PetscScalar* c = nullptr;
    check(VecGetArray(p.coordinates, &c), "VecGetArray");
    for (PetscInt row = 0; row < p.local_rows; ++row) {
      const PetscInt global = p.first_row + row;
      c[row] = nodes(global / 3, global % 3) - centre[global % 3];
    }
    check(VecRestoreArray(p.coordinates, &c), "VecRestoreArray");
  }
  check(MatNullSpaceCreateRigidBody(p.coordinates, &p.rigid_body_modes), "MatNullSpaceCreateRigidBody");
  check(VecCreateMPIWithArray(p.comm, 3, p.local_rows, p.n, nullptr, &p.b), "VecCreateMPIWithArray");
  check(VecCreateMPIWithArray(p.comm, 3, p.local_rows, p.n, nullptr, &p.x), "VecCreateMPIWithArray");

  check(KSPCreate(p.comm, &p.ksp), "KSPCreate");
  check(PetscObjectSetOptions(reinterpret_cast<PetscObject>(p.ksp), p.options), "PetscObjectSetOptions");
  PC pc = nullptr;
  check(KSPGetPC(p.ksp, &pc), "KSPGetPC");
  check(PetscObjectSetOptions(reinterpret_cast<PetscObject>(pc), p.options), "PetscObjectSetOptions");
  check(KSPSetTolerances(p.ksp, relative_tolerance, 0.0, PETSC_DEFAULT, max_iterations), "KSPSetTolerances");
  const DefaultOptionsWhileAlive own_options(p.options);
  check(KSPSetFromOptions(p.ksp), "KSPSetFromOptions (the options string)");

  // Eisenstat's trick applies SSOR of the preconditioner's matrix through a transformed operator built from that
  // same matrix: with a sparser copy the Krylov method would converge to the copy's solution, not the tangent's.
  PetscBool eisenstat = PETSC_FALSE;
  check(PetscObjectTypeCompare(reinterpret_cast<PetscObject>(pc), PCEISENSTAT, &eisenstat),
        "PetscObjectTypeCompare");
  if (eisenstat) {
    if (drop_tolerance > 0.0)
      throw std::invalid_argument(fmt::format(
          "PetscKrylovSolver: -pc_type eisenstat needs the tangent itself as the preconditioner's matrix, but a drop "
          "tolerance of {:g} was given (EfgOptions::preconditioner_drop_tolerance): set it to 0, or choose another "
          "preconditioner",
          drop_tolerance));
    PetscReal omega = 1.0;
    check(PCEisenstatGetOmega(pc, &omega), "PCEisenstatGetOmega");
    if (omega != 1.0)
      throw std::invalid_argument(fmt::format(
          "PetscKrylovSolver: -pc_eisenstat_omega {:g}: PETSc 3.18's Eisenstat preconditioner crashes with a "
          "relaxation factor other than 1 on this matrix format (in MatMultDiagonalBlock_SeqAIJ_Inode); leave it at "
          "1, or use -pc_type sor -pc_sor_omega {:g}",
          omega, omega));
  }
}

PetscKrylovSolver::~PetscKrylovSolver() = default;

Mat PetscKrylovSolver::Petsc::matrix(const SparseMatrix& a) {
  Petsc& p = *this;
  Mat m = nullptr;
  if (p.comm == PETSC_COMM_SELF) {
    // PETSc's AIJ format is CSR: reference the arrays (a 32k-node tangent is 1.25 GB).
    check(MatCreateSeqAIJWithArrays(PETSC_COMM_SELF, p.n, p.n, const_cast<PetscInt*>(a.outerIndexPtr()),
                                    const_cast<PetscInt*>(a.innerIndexPtr()), const_cast<PetscScalar*>(a.valuePtr()),
                                    &m),
          "MatCreateSeqAIJWithArrays");
  } else {
    // The owned rows, copied by PETSc into its diagonal and off-diagonal blocks.
    const PetscInt* starts = a.outerIndexPtr() + p.first_row;
    std::vector<PetscInt> local_row_starts(static_cast<std::size_t>(p.local_rows) + 1);  // CSR row pointer from 0
    for (PetscInt row = 0; row <= p.local_rows; ++row) local_row_starts[row] = starts[row] - starts[0];
    check(MatCreateMPIAIJWithArrays(p.comm, p.local_rows, p.local_rows, p.n, p.n, local_row_starts.data(),
                                    a.innerIndexPtr() + starts[0], a.valuePtr() + starts[0], &m),
          "MatCreateMPIAIJWithArrays");
  }
  check(MatSetBlockSize(m, 3), "MatSetBlockSize");
  return m;
}

void PetscKrylovSolver::set_matrix(const SparseMatrix& a) {
  Petsc& p = *petsc_;
  if (a.rows() != p.n || a.cols() != p.n || !a.isCompressed())
    throw std::invalid_argument(fmt::format(
        "PetscKrylovSolver::set_matrix: expected a compressed {} x {} matrix, got {} x {}", p.n, p.n, a.rows(),
        a.cols()));
  const auto t0 = std::chrono::steady_clock::now();
  if (p.a) check(MatDestroy(&p.a), "MatDestroy");
  p.a = p.matrix(a);
  check(MatSetNearNullSpace(p.a, p.rigid_body_modes), "MatSetNearNullSpace");
  if (p.p) check(MatDestroy(&p.p), "MatDestroy");
  Mat preconditioner_matrix = p.a;
  preconditioner_fill_ = 1.0;
  if (drop_tolerance_ > 0.0) {
    // Most of an EFG row's entries couple nodes whose supports barely overlap and are orders of magnitude below
    // the diagonal; the SOR sweeps and the aggregation read them all. Drop them from the preconditioner's copy
    // only: the near-null space of rough parameter vectors lives in the whole matrix, and preconditioning with
    // the sparser copy alone (the Krylov method on it too) stalls (docs/MESHLESS.md §2).
    const Eigen::VectorXd diagonal = a.diagonal().cwiseAbs();
    const double tol = drop_tolerance_;
    p.sparser = a;
    p.sparser.prune([&](const Eigen::Index& row, const Eigen::Index& col, const double& value) {
      return row / 3 == col / 3 || std::abs(value) >= tol * std::sqrt(diagonal[row] * diagonal[col]);
    });
    p.sparser.makeCompressed();
    preconditioner_fill_ = static_cast<double>(p.sparser.nonZeros()) / static_cast<double>(a.nonZeros());
    p.p = p.matrix(p.sparser);
    check(MatSetNearNullSpace(p.p, p.rigid_body_modes), "MatSetNearNullSpace");
    preconditioner_matrix = p.p;
  }
  check(KSPSetOperators(p.ksp, p.a, preconditioner_matrix), "KSPSetOperators");
  {
    // The node positions (centred), for preconditioners that aggregate by distance (ML's -pc_ml_Aux); the
    // others ignore them. After KSPSetOperators: ML takes the block size from the matrix.
    PC pc = nullptr;
    check(KSPGetPC(p.ksp, &pc), "KSPGetPC");
    PetscScalar* xyz = nullptr;
    check(VecGetArray(p.coordinates, &xyz), "VecGetArray");
    const PetscErrorCode set = PCSetCoordinates(pc, 3, p.local_rows / 3, xyz);
    check(VecRestoreArray(p.coordinates, &xyz), "VecRestoreArray");
    check(set, "PCSetCoordinates");
  }
  {
    const DefaultOptionsWhileAlive own_options(p.options);  // the level smoothers read theirs here
    check(KSPSetUp(p.ksp), "KSPSetUp (building the multigrid hierarchy)");
  }
  setup_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  // Levels and operator complexity of PETSc's own multigrid (GAMG); hypre and ML keep theirs inside.
  levels_ = 0;
  operator_complexity_ = 0.0;
  PC pc = nullptr;
  check(KSPGetPC(p.ksp, &pc), "KSPGetPC");
  PetscBool is_mg = PETSC_FALSE;
  check(PetscObjectTypeCompareAny(reinterpret_cast<PetscObject>(pc), &is_mg, PCGAMG, PCMG, PCML, ""),
        "PetscObjectTypeCompareAny");
  if (is_mg) {
    PetscInt nlevels = 0;
    check(PCMGGetLevels(pc, &nlevels), "PCMGGetLevels");
    double total = 0.0, fine = 0.0;
    for (PetscInt l = 0; l < nlevels; ++l) {
      KSP smoother = nullptr;
      Mat op = nullptr;
      check(PCMGGetSmoother(pc, l, &smoother), "PCMGGetSmoother");
      check(KSPGetOperators(smoother, &op, nullptr), "KSPGetOperators");
      MatInfo info;
      check(MatGetInfo(op, MAT_LOCAL, &info), "MatGetInfo");
      total += info.nz_used;
      if (l == nlevels - 1) fine = info.nz_used;
    }
    levels_ = static_cast<int>(nlevels);
    operator_complexity_ = fine > 0.0 ? total / fine : 0.0;
  }
}

Eigen::VectorXd PetscKrylovSolver::solve(const Eigen::VectorXd& b) {
  Petsc& p = *petsc_;
  if (!p.a) throw std::logic_error("PetscKrylovSolver::solve before set_matrix");
  if (b.size() != p.n) throw std::invalid_argument("PetscKrylovSolver::solve: wrong right-hand side size");
  Eigen::VectorXd x = Eigen::VectorXd::Zero(p.n);
  check(VecPlaceArray(p.b, b.data() + p.first_row), "VecPlaceArray");
  check(VecPlaceArray(p.x, x.data() + p.first_row), "VecPlaceArray");
  PetscErrorCode solved = 0;
  {
    const DefaultOptionsWhileAlive own_options(p.options);
    solved = KSPSolve(p.ksp, p.b, p.x);
  }
  check(VecResetArray(p.b), "VecResetArray");
  check(VecResetArray(p.x), "VecResetArray");
  check(solved, "KSPSolve");
  if (p.comm != PETSC_COMM_SELF)  // every process returns the whole solution
    check(MPI_Allgatherv(MPI_IN_PLACE, 0, MPI_DATATYPE_NULL, x.data(), p.row_counts.data(), p.row_offsets.data(),
                         MPI_DOUBLE, p.comm),
          "MPI_Allgatherv");
  PetscInt its = 0;
  KSPConvergedReason reason;
  check(KSPGetIterationNumber(p.ksp, &its), "KSPGetIterationNumber");
  check(KSPGetConvergedReason(p.ksp, &reason), "KSPGetConvergedReason");
  last_iterations_ = static_cast<int>(its);
  if (reason < 0) {
    PetscReal residual = 0.0;
    KSPGetResidualNorm(p.ksp, &residual);
    throw std::runtime_error(fmt::format(
        "{} did not converge: {} after {} iterations (residual {:.3e}, |b| = {:.3e}); raise "
        "iterative_max_iterations, or use the direct solver if the LU fits in memory",
        description(), KSPConvergedReasons[reason], its, residual, b.norm()));
  }
  return x;
}

std::pair<int, int> PetscKrylovSolver::owned_nodes() const {
  return {static_cast<int>(petsc_->first_row / 3), static_cast<int>((petsc_->first_row + petsc_->local_rows) / 3)};
}

std::string PetscKrylovSolver::description() const {
  const Petsc& p = *petsc_;
  KSPType ksp_type = nullptr;
  PCType pc_type = nullptr;
  PC pc = nullptr;
  KSPGetType(p.ksp, &ksp_type);
  KSPGetPC(p.ksp, &pc);
  PCGetType(pc, &pc_type);
  std::string s = fmt::format("PETSc {} + {}", ksp_type ? ksp_type : "?", pc_type ? pc_type : "?");
  if (p.comm != PETSC_COMM_SELF) s += fmt::format(" on {} MPI processes", p.row_counts.size());
  if (levels_ > 0) s += fmt::format(" ({} levels, operator complexity {:.2f})", levels_, operator_complexity_);
  if (drop_tolerance_ > 0.0)
    s += fmt::format(", preconditioner built from {:.0f} % of the entries (drop tolerance {:g})",
                     100.0 * preconditioner_fill_, drop_tolerance_);
  return s;
}

}  // namespace meshless
