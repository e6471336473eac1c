#pragma once
// main() of the benchmark programs: MPI initialised through deal.II (the FEM runs on Trilinos/PETSc MPI
// objects), every process runs the same benchmarks in lock-step (fixed iteration counts, collective solves),
// and only rank 0 prints and writes the --benchmark_out report.
//   build/bin/bench_fem ...                       one process
//   mpirun -np 2 build/bin/bench_fem ...          the distributed cases run on both processes
#include <benchmark/benchmark.h>
#include <deal.II/base/mpi.h>

#include <cstring>
#include <functional>
#include <vector>

#include "core/mpi_session_directory.hpp"
#include "core/openblas_kernel.hpp"

namespace bench {

/// A reporter that prints nothing (the processes other than rank 0).
class NullReporter : public benchmark::BenchmarkReporter {
 public:
  bool ReportContext(const Context&) override { return true; }
  void ReportRuns(const std::vector<Run>&) override {}
};

/// Google Benchmark on every process in lock-step; rank 0 alone prints and writes the --benchmark_out report.
/// MPI must be initialised. Returns main()'s exit code.
inline int run_specified_benchmarks_on_every_process(int argc, char** argv) {
  const bool root = dealii::Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0;
  std::vector<char*> args;
  for (int i = 0; i < argc; ++i)
    if (root || std::strncmp(argv[i], "--benchmark_out", 15) != 0) args.push_back(argv[i]);
  int n = static_cast<int>(args.size());
  benchmark::Initialize(&n, args.data());
  if (benchmark::ReportUnrecognizedArguments(n, args.data())) return 1;
  if (root) {
    benchmark::RunSpecifiedBenchmarks();
  } else {
    NullReporter quiet;
    benchmark::RunSpecifiedBenchmarks(&quiet);
  }
  benchmark::Shutdown();
  return 0;
}

inline int run_benchmarks_under_mpi(int argc, char** argv) {
  core::use_supported_openblas_kernel(argv);  // before MPI: it may run the program again
  const core::SingletonMpiSessionDirectory session_directory;  // outlives MPI
  dealii::Utilities::MPI::MPI_InitFinalize mpi(argc, argv);
  return run_specified_benchmarks_on_every_process(argc, argv);
}

/// main() of the EFG benchmarks, whose models may pick the PETSc Krylov solver: only the program name is passed on
/// to PETSc, so that it does not read Google Benchmark's flags; `before_finalize` releases anything that holds PETSc
/// objects (a cached model) while PETSc is still initialised. Under `mpirun -np N` every process builds the same
/// model and the Krylov solves are distributed over them (meshless/solvers/petsc_krylov_solver.hpp); only rank 0 prints
/// and writes the --benchmark_out report.
inline int run_benchmarks_with_petsc(int argc, char** argv, const std::function<void()>& before_finalize = {}) {
  core::use_supported_openblas_kernel(argv);  // before MPI: it may run the program again
  int petsc_argc = 1;
  const core::SingletonMpiSessionDirectory session_directory;  // outlives MPI
  dealii::Utilities::MPI::MPI_InitFinalize mpi(petsc_argc, argv, 1);
  const int code = run_specified_benchmarks_on_every_process(argc, argv);
  if (before_finalize) before_finalize();
  return code;
}

}  // namespace bench
