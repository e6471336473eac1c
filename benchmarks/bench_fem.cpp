// FEM reference: time per Newton iteration and peak memory against the DOFs, and the speed-up of two MPI
// processes over one (docs/PERFORMANCE.md, "FEM reference"). reference_fem::run_block_benchmark: a block of the
// lung material (k = 1, non-symmetric tangent) at n = 5, 8, 12, 16, 21 elements through its depth (16k to 1.1M
// DOFs), two time steps.
//   BM_FemBlock/amg/one_process/n      AMG, one process with two assembly threads
//   BM_FemBlock/direct/one_process/n   UMFPACK-preconditioned GMRES (the earlier solver), n <= 12
//   BM_FemBlock/amg/all_processes/n    AMG on every process of the job, one assembly thread each
// Run the last ones under `mpirun -np 2` to measure the speed-up in the same run as the one-process figures
// (the one-process benchmarks then run on rank 0 while rank 1 waits). Time = assembly + linear solves of
// both steps (manual time); set-up and peak memory (summed over the processes) are counters.
#include <benchmark/benchmark.h>
#include <deal.II/base/mpi.h>

#include <thread>

#include "benchmarks/mpi_benchmark_main.hpp"
#include "reference_fem/block_benchmark.hpp"

namespace {

using reference_fem::LinearSolverType;

void BM_FemBlock(benchmark::State& state, LinearSolverType solver, bool all_processes) {
  const int n_processes = static_cast<int>(dealii::Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD));
  const bool root = dealii::Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0;
  if (all_processes && n_processes == 1) {
    state.SkipWithError("run under mpirun -np 2 (or more) for the distributed figures");
    return;
  }
  reference_fem::BlockBenchmarkOptions options;
  options.subdivisions = static_cast<int>(state.range(0));
  options.linear_solver = solver;
  options.communicator = all_processes ? MPI_COMM_WORLD : MPI_COMM_SELF;
  // The node's two cores: both threads for one process, one thread each for two.
  const unsigned int cores = std::max(1u, std::thread::hardware_concurrency());
  options.threads = all_processes ? std::max(1u, cores / static_cast<unsigned int>(n_processes)) : cores;
  reference_fem::BlockBenchmarkResult result;
  for (auto _ : state) {
    if (all_processes || root) result = reference_fem::run_block_benchmark(options);
    MPI_Barrier(MPI_COMM_WORLD);  // the other processes wait for a one-process run
    state.SetIterationTime(result.newton_seconds);
  }
  state.counters["dofs"] = static_cast<double>(result.n_dofs);
  state.counters["processes"] = all_processes ? n_processes : 1;
  state.counters["newton_iterations"] = result.newton_iterations;
  int linear_iterations = 0;
  for (const auto& s : result.steps) linear_iterations += s.linear_iterations;
  state.counters["gmres_iterations"] = linear_iterations;
  state.counters["s_per_newton_iteration"] = result.seconds_per_newton_iteration;
  state.counters["setup_s"] = result.setup_seconds;
  state.counters["peak_memory_MB"] = result.peak_memory_mb;
  state.counters["bytes_per_dof"] = result.peak_memory_mb * 1024.0 * 1024.0 / static_cast<double>(result.n_dofs);
}

}  // namespace

int main(int argc, char** argv) {
  for (const int n : {5, 8, 12, 16, 21})
    benchmark::RegisterBenchmark("BM_FemBlock/amg/one_process", BM_FemBlock,
                                 LinearSolverType::amg, false)
        ->Arg(n)
        ->UseManualTime()
        ->Iterations(1)
        ->Unit(benchmark::kMillisecond);
  for (const int n : {5, 8, 12})
    benchmark::RegisterBenchmark("BM_FemBlock/direct/one_process", BM_FemBlock,
                                 LinearSolverType::direct, false)
        ->Arg(n)
        ->UseManualTime()
        ->Iterations(1)
        ->Unit(benchmark::kMillisecond);
  for (const int n : {5, 8, 12, 16, 21})
    benchmark::RegisterBenchmark("BM_FemBlock/amg/all_processes", BM_FemBlock,
                                 LinearSolverType::amg, true)
        ->Arg(n)
        ->UseManualTime()
        ->Iterations(1)
        ->Unit(benchmark::kMillisecond);
  return bench::run_benchmarks_under_mpi(argc, argv);
}
