#include "benchmarks/preconditioner_study.hpp"

#include <deal.II/base/mpi.h>
#include <deal.II/distributed/fully_distributed_tria.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/lac/dynamic_sparsity_pattern.h>
#include <deal.II/lac/solver_control.h>
#include <deal.II/lac/solver_gmres.h>
#include <deal.II/lac/sparse_direct.h>
#include <deal.II/lac/sparse_matrix.h>
#include <deal.II/lac/sparsity_pattern.h>
#include <deal.II/lac/trilinos_precondition.h>
#include <deal.II/lac/trilinos_sparse_matrix.h>
#include <deal.II/lac/trilinos_vector.h>

#include <Epetra_CrsMatrix.h>
#include <fmt/format.h>
#include <petscksp.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <functional>
#include <memory>
#include <stdexcept>

#include "reference_fem/amg_preconditioner.hpp"
#include "reference_fem/distributed_triangulation.hpp"
#include "reference_fem/triangulation_from_mesh.hpp"
#include "reference_fem/viscoelastic_solver.hpp"

namespace reference_fem {
namespace {

using namespace dealii;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// CPU time of this process, all threads [s].
double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

void check(PetscErrorCode code, const char* call) {
  if (code != 0) throw std::runtime_error(fmt::format("compare_preconditioners: PETSc {} failed ({})", call, code));
}

constexpr int kMaxIterations = 1000;
constexpr unsigned int kRestart = 60;

/// The Trilinos matrix as a PETSc AIJ matrix with block size 3 (nodes), same rows on the same processes.
Mat to_petsc(const TrilinosWrappers::SparseMatrix& a, MPI_Comm communicator) {
  const Epetra_CrsMatrix& e = a.trilinos_matrix();
  const auto range = a.local_range();
  const PetscInt n_local = static_cast<PetscInt>(range.second - range.first);
  std::vector<PetscInt> d_nnz(n_local, 0), o_nnz(n_local, 0);
  for (int i = 0; i < n_local; ++i) {
    int n;
    double* values;
    int* columns;
    e.ExtractMyRowView(i, n, values, columns);
    for (int k = 0; k < n; ++k) {
      const auto column = static_cast<types::global_dof_index>(e.ColMap().GID(columns[k]));
      (column >= range.first && column < range.second ? d_nnz : o_nnz)[i] += 1;
    }
  }
  Mat m;
  check(MatCreate(communicator, &m), "MatCreate");
  check(MatSetSizes(m, n_local, n_local, static_cast<PetscInt>(a.m()), static_cast<PetscInt>(a.n())), "MatSetSizes");
  check(MatSetType(m, MATAIJ), "MatSetType");
  check(MatSetBlockSize(m, 3), "MatSetBlockSize");
  check(MatSeqAIJSetPreallocation(m, 0, d_nnz.data()), "MatSeqAIJSetPreallocation");
  check(MatMPIAIJSetPreallocation(m, 0, d_nnz.data(), 0, o_nnz.data()), "MatMPIAIJSetPreallocation");
  std::vector<PetscInt> global_columns;
  for (int i = 0; i < n_local; ++i) {
    int n;
    double* values;
    int* columns;
    e.ExtractMyRowView(i, n, values, columns);
    global_columns.resize(n);
    for (int k = 0; k < n; ++k) global_columns[k] = e.ColMap().GID(columns[k]);
    const PetscInt row = static_cast<PetscInt>(range.first) + i;
    check(MatSetValues(m, 1, &row, n, global_columns.data(), values, INSERT_VALUES), "MatSetValues");
  }
  check(MatAssemblyBegin(m, MAT_FINAL_ASSEMBLY), "MatAssemblyBegin");
  check(MatAssemblyEnd(m, MAT_FINAL_ASSEMBLY), "MatAssemblyEnd");
  return m;
}

Vec to_petsc(const TrilinosWrappers::MPI::Vector& v, MPI_Comm communicator) {
  Vec p;
  check(VecCreateMPI(communicator, static_cast<PetscInt>(v.locally_owned_size()), static_cast<PetscInt>(v.size()), &p),
        "VecCreateMPI");
  check(VecSetBlockSize(p, 3), "VecSetBlockSize");
  PetscScalar* values;
  check(VecGetArray(p, &values), "VecGetArray");
  std::copy(v.begin(), v.end(), values);
  check(VecRestoreArray(p, &values), "VecRestoreArray");
  return p;
}

/// The coordinate of each owned DoF's support point along the DoF's own component (what
/// MatNullSpaceCreateRigidBody reads, with block size 3).
Vec support_coordinates(const DoFHandler<3>& dof_handler, const Mapping<3>& mapping, const IndexSet& owned,
                        MPI_Comm communicator) {
  Vec coordinates;
  check(VecCreateMPI(communicator, static_cast<PetscInt>(owned.n_elements()), static_cast<PetscInt>(owned.size()),
                     &coordinates),
        "VecCreateMPI");
  check(VecSetBlockSize(coordinates, 3), "VecSetBlockSize");
  PetscScalar* values;
  check(VecGetArray(coordinates, &values), "VecGetArray");
  const FiniteElement<3>& fe = dof_handler.get_fe();
  FEValues<3> fe_values(mapping, fe, Quadrature<3>(fe.get_unit_support_points()), update_quadrature_points);
  std::vector<types::global_dof_index> dofs(fe.n_dofs_per_cell());
  for (const auto& cell : dof_handler.active_cell_iterators()) {
    if (!cell->is_locally_owned()) continue;
    fe_values.reinit(cell);
    cell->get_dof_indices(dofs);
    for (unsigned int i = 0; i < dofs.size(); ++i)
      if (owned.is_element(dofs[i]))
        values[owned.index_within_set(dofs[i])] = fe_values.quadrature_point(i)[fe.system_to_component_index(i).first];
  }
  check(VecRestoreArray(coordinates, &values), "VecRestoreArray");
  return coordinates;
}

const char* const kMlRigid = "ML SA, rigid-body modes";
const char* const kMlTranslations = "ML SA, translations only";
const char* const kMlThreshold = "ML SA, rigid-body modes, threshold 0.02";
const char* const kMlChebyshev4 = "ML SA, rigid-body modes, Chebyshev degree 4";
const char* const kMlWCycle = "ML SA, rigid-body modes, W-cycle";
const char* const kMlGaussSeidel = "ML SA, rigid-body modes, symmetric Gauss-Seidel (1 sweep)";
const char* const kMlLowOrder = "ML SA, rigid-body modes, higher_order_elements = false";
const char* const kGamg = "GAMG, rigid-body modes";
const char* const kGamgThreshold = "GAMG, rigid-body modes, threshold 0.02";
const char* const kBoomerScalar = "BoomerAMG, scalar defaults";
const char* const kBoomerNodal =
    "BoomerAMG, nodal systems (HMIS, ext+i, strong 0.5, nodal coarsening, vector interpolation)";
const char* const kUmfpack = "UMFPACK LU";

}  // namespace

std::vector<std::string> preconditioner_candidates() {
  return {kMlRigid,  kMlTranslations, kMlThreshold,  kMlChebyshev4, kMlWCycle, kMlGaussSeidel,
          kMlLowOrder, kGamg,         kGamgThreshold, kBoomerScalar, kBoomerNodal, kUmfpack};
}

PreconditionerStudy compare_preconditioners(const core::TetMesh& mesh, const SolverParameters& parameters,
                                            const BoundaryConditions& conditions, double t, double tolerance,
                                            MPI_Comm communicator, const std::vector<std::string>& only) {
  auto whole = std::make_unique<Triangulation<3>>();
  build_triangulation(mesh, whole.get());
  parallel::fullydistributed::Triangulation<3> triangulation(communicator);
  distribute_triangulation(whole.get(), &triangulation);
  whole.reset();
  SolverParameters p = parameters;
  p.newton.linear = LinearSolverParameters::for_type(LinearSolverType::amg);
  ViscoelasticSolver solver(triangulation, p, conditions);
  solver.setup_system();
  PreconditionerStudy study;
  study.n_dofs = solver.dof_handler().n_dofs();
  auto start = Clock::now();
  solver.assemble_newton_system(t);
  study.assembly_seconds = seconds_since(start);
  const TrilinosWrappers::SparseMatrix& a = solver.system_matrix();
  const TrilinosWrappers::MPI::Vector& b = solver.system_rhs();
  const double b_norm = b.l2_norm();
  const auto modes = rigid_body_modes(solver.dof_handler(), solver.mapping(), solver.locally_owned_dofs(),
                                      a.trilinos_matrix().DomainMap());
  const auto wanted = [&](const std::string& name) {
    if (only.empty()) return true;
    return std::find(only.begin(), only.end(), name) != only.end();
  };
  const auto true_residual = [&](const TrilinosWrappers::MPI::Vector& x) {
    TrilinosWrappers::MPI::Vector r(b);
    a.vmult(r, x);
    r.sadd(-1.0, 1.0, b);
    return r.l2_norm() / b_norm;
  };

  const auto ml = [&](const std::string& name, const AmgOptions& options) {
    if (!wanted(name)) return;
    PreconditionerTrial trial;
    trial.name = name;
    start = Clock::now();
    double cpu = cpu_seconds();
    TrilinosWrappers::PreconditionAMG amg;
    amg.initialize(a, ml_parameters(a, *modes, options));
    trial.setup_seconds = seconds_since(start);
    trial.setup_cpu_seconds = cpu_seconds() - cpu;
    TrilinosWrappers::MPI::Vector x(b);
    x = 0.0;
    SolverControl control(kMaxIterations, tolerance * b_norm, false, false);
    SolverGMRES<TrilinosWrappers::MPI::Vector> gmres(
        control, SolverGMRES<TrilinosWrappers::MPI::Vector>::AdditionalData(kRestart + 2, true));
    start = Clock::now();
    cpu = cpu_seconds();
    try {
      gmres.solve(a, x, b, amg);
      trial.converged = true;
    } catch (const SolverControl::NoConvergence&) {
    }
    trial.solve_seconds = seconds_since(start);
    trial.solve_cpu_seconds = cpu_seconds() - cpu;
    trial.iterations = static_cast<int>(control.last_step());
    trial.relative_residual = true_residual(x);
    study.trials.push_back(trial);
  };
  AmgOptions options;
  options.higher_order_elements = parameters.degree > 1;
  ml(kMlRigid, options);
  {
    AmgOptions o = options;
    o.rigid_body_modes = false;
    ml(kMlTranslations, o);
  }
  {
    AmgOptions o = options;
    o.aggregation_threshold = 0.02;
    ml(kMlThreshold, o);
  }
  {
    AmgOptions o = options;
    o.smoother_sweeps = 4;
    ml(kMlChebyshev4, o);
  }
  {
    AmgOptions o = options;
    o.w_cycle = true;
    ml(kMlWCycle, o);
  }
  {
    AmgOptions o = options;
    o.smoother_type = "symmetric Gauss-Seidel";
    o.smoother_sweeps = 1;
    ml(kMlGaussSeidel, o);
  }
  {
    AmgOptions o = options;
    o.higher_order_elements = false;
    ml(kMlLowOrder, o);
  }

  // PETSc: the same matrix and right-hand side, and its own GMRES(60), right-preconditioned (the
  // unpreconditioned residual is measured, as above).
  bool any_petsc = false;
  for (const auto& name : preconditioner_candidates())
    any_petsc |= wanted(name) && (name.rfind("GAMG", 0) == 0 || name.rfind("BoomerAMG", 0) == 0);
  if (any_petsc) {
    Mat pa = to_petsc(a, communicator);
    Vec pb = to_petsc(b, communicator);
    Vec coordinates = support_coordinates(solver.dof_handler(), solver.mapping(), solver.locally_owned_dofs(),
                                          communicator);
    MatNullSpace near_null_space;
    check(MatNullSpaceCreateRigidBody(coordinates, &near_null_space), "MatNullSpaceCreateRigidBody");
    check(MatSetNearNullSpace(pa, near_null_space), "MatSetNearNullSpace");
    int counter = 0;
    const auto petsc = [&](const std::string& name, const std::function<void(PC, const std::string&)>& configure) {
      if (!wanted(name)) return;
      PreconditionerTrial trial;
      trial.name = name;
      const std::string prefix = fmt::format("study{}_", counter++);
      KSP ksp;
      PC pc;
      check(KSPCreate(communicator, &ksp), "KSPCreate");
      check(KSPSetOptionsPrefix(ksp, prefix.c_str()), "KSPSetOptionsPrefix");
      check(KSPSetOperators(ksp, pa, pa), "KSPSetOperators");
      check(KSPSetType(ksp, KSPGMRES), "KSPSetType");
      check(KSPGMRESSetRestart(ksp, kRestart), "KSPGMRESSetRestart");
      check(KSPSetPCSide(ksp, PC_RIGHT), "KSPSetPCSide");
      check(KSPSetTolerances(ksp, tolerance, 1e-300, PETSC_DEFAULT, kMaxIterations), "KSPSetTolerances");
      check(KSPGetPC(ksp, &pc), "KSPGetPC");
      configure(pc, "-" + prefix);
      check(KSPSetFromOptions(ksp), "KSPSetFromOptions");
      Vec px;
      check(VecDuplicate(pb, &px), "VecDuplicate");
      check(VecSet(px, 0.0), "VecSet");
      start = Clock::now();
      double cpu = cpu_seconds();
      check(KSPSetUp(ksp), "KSPSetUp");
      check(PCSetUp(pc), "PCSetUp");
      trial.setup_seconds = seconds_since(start);
      trial.setup_cpu_seconds = cpu_seconds() - cpu;
      start = Clock::now();
      cpu = cpu_seconds();
      check(KSPSolve(ksp, pb, px), "KSPSolve");
      trial.solve_seconds = seconds_since(start);
      trial.solve_cpu_seconds = cpu_seconds() - cpu;
      PetscInt iterations;
      KSPConvergedReason reason;
      check(KSPGetIterationNumber(ksp, &iterations), "KSPGetIterationNumber");
      check(KSPGetConvergedReason(ksp, &reason), "KSPGetConvergedReason");
      trial.iterations = static_cast<int>(iterations);
      trial.converged = reason > 0;
      Vec r;
      PetscReal r_norm, pb_norm;
      check(VecDuplicate(pb, &r), "VecDuplicate");
      check(MatMult(pa, px, r), "MatMult");
      check(VecAYPX(r, -1.0, pb), "VecAYPX");
      check(VecNorm(r, NORM_2, &r_norm), "VecNorm");
      check(VecNorm(pb, NORM_2, &pb_norm), "VecNorm");
      trial.relative_residual = r_norm / pb_norm;
      VecDestroy(&r);
      VecDestroy(&px);
      KSPDestroy(&ksp);
      study.trials.push_back(trial);
    };
    const auto option = [](const std::string& prefix, const char* key, const char* value) {
      check(PetscOptionsSetValue(nullptr, (prefix + key).c_str(), value), "PetscOptionsSetValue");
    };
    petsc(kGamg, [](PC pc, const std::string&) { check(PCSetType(pc, PCGAMG), "PCSetType"); });
    petsc(kGamgThreshold, [&](PC pc, const std::string& prefix) {
      check(PCSetType(pc, PCGAMG), "PCSetType");
      option(prefix, "pc_gamg_threshold", "0.02");
    });
    petsc(kBoomerScalar, [](PC pc, const std::string&) {
      check(PCSetType(pc, PCHYPRE), "PCSetType");
      check(PCHYPRESetType(pc, "boomeramg"), "PCHYPRESetType");
    });
    petsc(kBoomerNodal, [&](PC pc, const std::string& prefix) {
            check(PCSetType(pc, PCHYPRE), "PCSetType");
            check(PCHYPRESetType(pc, "boomeramg"), "PCHYPRESetType");
            option(prefix, "pc_hypre_boomeramg_coarsen_type", "HMIS");
            option(prefix, "pc_hypre_boomeramg_interp_type", "ext+i");
            option(prefix, "pc_hypre_boomeramg_strong_threshold", "0.5");
            option(prefix, "pc_hypre_boomeramg_nodal_coarsen", "6");
            option(prefix, "pc_hypre_boomeramg_vec_interp_variant", "3");
          });
    MatNullSpaceDestroy(&near_null_space);
    VecDestroy(&coordinates);
    VecDestroy(&pb);
    MatDestroy(&pa);
  }

  if (wanted(kUmfpack) && Utilities::MPI::n_mpi_processes(communicator) == 1) {
    PreconditionerTrial trial;
    trial.name = kUmfpack;
    start = Clock::now();
    double cpu = cpu_seconds();
    DynamicSparsityPattern dsp(a.m());
    for (types::global_dof_index row = 0; row < a.m(); ++row)
      for (auto entry = a.begin(row); entry != a.end(row); ++entry) dsp.add(row, entry->column());
    SparsityPattern pattern;
    pattern.copy_from(dsp);
    SparseMatrix<double> copy(pattern);
    copy.copy_from(a);
    SparseDirectUMFPACK lu;
    lu.initialize(copy);
    trial.setup_seconds = seconds_since(start);
    trial.setup_cpu_seconds = cpu_seconds() - cpu;
    Vector<double> x(b.size()), rhs(b.size());
    std::copy(b.begin(), b.end(), rhs.begin());
    start = Clock::now();
    cpu = cpu_seconds();
    lu.vmult(x, rhs);
    trial.solve_seconds = seconds_since(start);
    trial.solve_cpu_seconds = cpu_seconds() - cpu;
    TrilinosWrappers::MPI::Vector tx(b);
    std::copy(x.begin(), x.end(), tx.begin());
    trial.relative_residual = true_residual(tx);
    trial.converged = true;
    study.trials.push_back(trial);
  }
  return study;
}

}  // namespace reference_fem
