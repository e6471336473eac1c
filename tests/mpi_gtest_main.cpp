// GoogleTest main() of the suites that run the FEM reference: MPI (with PETSc and Trilinos) initialised
// through deal.II. Under mpirun every process runs every test (the FEM calls are collective) and only rank 0
// prints the results.
#include <deal.II/base/mpi.h>
#include <gtest/gtest.h>

#include "core/mpi_session_directory.hpp"
#include "core/openblas_kernel.hpp"

int main(int argc, char** argv) {
  core::use_supported_openblas_kernel(argv);  // before MPI: it may run the program again
  const core::SingletonMpiSessionDirectory session_directory;  // outlives MPI: ctest runs suites side by side
  dealii::Utilities::MPI::MPI_InitFinalize mpi(argc, argv);
  ::testing::InitGoogleTest(&argc, argv);
  if (dealii::Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) != 0) {
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  return RUN_ALL_TESTS();
}
