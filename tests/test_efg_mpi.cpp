// The EFG model's Krylov solve distributed over two processes, against MUMPS on each process alone. Run under
// `mpirun -np 2` (ctest: test_efg_mpi_np2, label `mpi`). Every process builds the same model and assembles only the
// rows it owns; the PETSc solve (LGMRES + SSOR by Eisenstat's trick, local to each process) returns the whole
// solution to both (meshless/solvers/petsc_krylov_solver.hpp). The nonlinear law (k = 2: a non-symmetric tangent that
// changes at every Newton iteration) over an elastic and two creep steps.
#include <deal.II/base/mpi.h>
#include <gtest/gtest.h>
#include <mpi.h>

#include <iostream>
#include <stdexcept>
#include <string>

#include "meshless/verification/box_mesh.hpp"
#include "meshless/efg/efg_model.hpp"
#include "meshless/solvers/petsc_krylov_solver.hpp"
#include "meshless/verification/verification_problems.hpp"
#include "core/geometry_broadcast.hpp"
#include "tests/sheared_box_runs.hpp"

namespace meshless {
namespace {

/// Largest |a - b| over the processes, with b rank 0's vector.
/// Every test here compares two processes with one: on any other count it fails (a skip would report "Passed").
constexpr const char* kRunOnTwoProcesses = "run under mpirun -np 2 (ctest: test_efg_mpi_np2)";

double largest_difference_from_rank_zero(const Eigen::VectorXd& a) {
  Eigen::VectorXd rank_zero = a;
  MPI_Bcast(rank_zero.data(), static_cast<int>(rank_zero.size()), MPI_DOUBLE, 0, MPI_COMM_WORLD);
  double local = (a - rank_zero).cwiseAbs().maxCoeff(), largest = 0.0;
  MPI_Allreduce(&local, &largest, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return largest;
}

TEST(EfgMpi, DistributedKrylovSolveReachesTheDirectSolutionWithNonzeroK) {
  if (petsc_processes() != 2) GTEST_FAIL() << kRunOnTwoProcesses;
  // The 8^3 box with k = 2: an elastic step and two creep steps of 0.1 s.
  const Eigen::VectorXd direct = solve_sheared_box(8, LinearSolverKind::direct, nullptr, 2.0, 3);  // MUMPS, alone
  EfgStatistics stats;
  int iterations = 0;
  const Eigen::VectorXd distributed =
      solve_sheared_box(8, LinearSolverKind::petsc_krylov, &stats, 2.0, 3, &iterations);
  const double difference = (distributed - direct).norm() / direct.norm();
  if (dealii::Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0)
    std::cout << "8^3 sheared box, k = 2, three steps: " << stats.linear_solver << ", " << iterations
              << " iterations; relative difference from MUMPS " << difference << "\n";
  EXPECT_EQ(stats.linear_solver, "PETSc lgmres + eisenstat on 2 MPI processes");
  // Both stop at Newton's tolerance 1e-8 by different Newton paths: measured 1.2e-11.
  EXPECT_LT(difference, 1e-10);
  // Every process returns the whole solution and runs the same Newton iterations from it.
  EXPECT_EQ(largest_difference_from_rank_zero(distributed), 0.0);
}

TEST(EfgMpi, AutomaticChoiceDistributesTheKrylovSolveRatherThanRepeatTheFactorisation) {
  if (petsc_processes() != 2) GTEST_FAIL() << kRunOnTwoProcesses;
  // One process would factorise this small cloud (EfgLinearSolvers.AutomaticChoiceFactorisesSmallClouds...).
  EfgModel model(sheared_box_problem(5));
  model.setup_system();
  model.solve_step(1);
  EXPECT_EQ(model.statistics().linear_solver, "PETSc lgmres + eisenstat on 2 MPI processes");
}

TEST(EfgMpi, DistributedSolveRefusesADropToleranceAndSaysWhatToChange) {
  // The sparser preconditioner copy compares each entry with the diagonal of both its rows; a distributed solve
  // assembles only this process's rows, so the others' diagonal is not there to compare with.
  if (petsc_processes() != 2) GTEST_FAIL() << kRunOnTwoProcesses;
  const core::PointMatrix nodes = sheared_box_problem(3).mesh.vertices;
  try {
    PetscKrylovSolver solver(nodes, kMlWithGcrSmoothersOptions, 1e-9, 100, 0.01);
    FAIL() << "a drop tolerance was accepted by a distributed solve";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("distributed_krylov_solve = false"), std::string::npos) << e.what();
  }
  // On each process alone it is accepted.
  EXPECT_NO_THROW(PetscKrylovSolver(nodes, kMlWithGcrSmoothersOptions, 1e-9, 100, 0.01, /*distributed=*/false));
}

TEST(EfgMpi, EveryProcessGetsRankZerosNodeCloud) {
  // `mpirun -np N tissue solve meshless` meshes on rank 0 alone (core::build_on_rank_zero); every process
  // must then build the same EFG model, so the node cloud must arrive whole: vertices, cells, faces and their tags.
  if (petsc_processes() != 2) GTEST_FAIL() << kRunOnTwoProcesses;
  const EfgProblem box = sheared_box_problem(4);
  const core::Geometry g = core::build_on_rank_zero(
      [&] {
        core::Geometry built;
        built.meshless_mesh = box.mesh;
        built.sample_points = box.mesh.vertices.topRows(2);
        return built;
      },
      MPI_COMM_WORLD);
  const core::TetMesh& m = g.meshless_mesh;
  EXPECT_EQ(m.vertices, box.mesh.vertices);  // the same box on every process (make_box_mesh's fixed seed)
  EXPECT_EQ(m.tets, box.mesh.tets);
  EXPECT_EQ(m.boundary_faces, box.mesh.boundary_faces);
  EXPECT_EQ(m.face_tags, box.mesh.face_tags);
  EXPECT_EQ(m.vertex_fixed, box.mesh.vertex_fixed);
  EXPECT_EQ(g.sample_points.rows(), 2);
  EXPECT_EQ(g.fem_mesh.num_vertices(), 0);
}

}  // namespace
}  // namespace meshless
