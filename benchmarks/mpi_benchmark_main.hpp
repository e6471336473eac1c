#pragma once
// main() for the benchmarks whose models may pick the AMG-Krylov solver (PETSc): MPI and PETSc are initialised
// before the benchmarks run and finalised after them. Only the program name is passed to PETSc, so that it does
// not read Google Benchmark's flags.
#include <benchmark/benchmark.h>
#include <deal.II/base/mpi.h>

#include <functional>

namespace benchmarks {

/// Runs the registered benchmarks; `before_finalize` releases anything that holds PETSc objects (a cached
/// model) while PETSc is still initialised.
inline int run_with_mpi(int argc, char** argv, const std::function<void()>& before_finalize = {}) {
  int petsc_argc = 1;
  dealii::Utilities::MPI::MPI_InitFinalize mpi(petsc_argc, argv, 1);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  if (before_finalize) before_finalize();
  return 0;
}

}  // namespace benchmarks
