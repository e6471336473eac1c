#pragma once
// main() of the FEM benchmark programs: MPI initialised through deal.II (the FEM runs on Trilinos/PETSc MPI
// objects), every process runs the same benchmarks in lock-step (fixed iteration counts, collective solves),
// and only rank 0 prints and writes the --benchmark_out report.
//   build/bin/bench_fem ...                       one process
//   mpirun -np 2 build/bin/bench_fem ...          the distributed cases run on both processes
#include <benchmark/benchmark.h>
#include <deal.II/base/mpi.h>

#include <cstring>
#include <functional>
#include <vector>

namespace bench {

/// A reporter that prints nothing (the processes other than rank 0).
class NullReporter : public benchmark::BenchmarkReporter {
 public:
  bool ReportContext(const Context&) override { return true; }
  void ReportRuns(const std::vector<Run>&) override {}
};

inline int run_benchmarks_under_mpi(int argc, char** argv) {
  dealii::Utilities::MPI::MPI_InitFinalize mpi(argc, argv);
  const bool root = dealii::Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0;
  std::vector<char*> args;
  for (int i = 0; i < argc; ++i)
    if (root || std::strncmp(argv[i], "--benchmark_out", 15) != 0) args.push_back(argv[i]);
  int n = static_cast<int>(args.size());
  benchmark::Initialize(&n, args.data());
  if (root) {
    benchmark::RunSpecifiedBenchmarks();
  } else {
    NullReporter quiet;
    benchmark::RunSpecifiedBenchmarks(&quiet);
  }
  benchmark::Shutdown();
  return 0;
}

/// main() of the one-process EFG benchmarks whose models may pick the AMG-Krylov solver (PETSc): only the program
/// name is passed on, so that PETSc does not read Google Benchmark's flags; `before_finalize` releases anything that
/// holds PETSc objects (a cached model) while PETSc is still initialised.
inline int run_benchmarks_with_petsc(int argc, char** argv, const std::function<void()>& before_finalize = {}) {
  int petsc_argc = 1;
  dealii::Utilities::MPI::MPI_InitFinalize mpi(petsc_argc, argv, 1);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  if (before_finalize) before_finalize();
  return 0;
}

}  // namespace bench
