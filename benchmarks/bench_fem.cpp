// FEM reference speed (docs/PERFORMANCE.md, "FEM reference").
//
// BM_LungSmall/{amg,direct}: configs/lung_small.json at its shipped 12 mm, the whole 10-step solve
// (reference_fem::run_case, geometry built once), with the AMG solver and with the direct one (GMRES
// preconditioned by UMFPACK LU factors, the earlier solver), in one run; the direct run reports its largest
// sample difference to the AMG run.
//
// BM_FemBlock: time per Newton iteration and peak memory against the DOFs, and the speed-up of two MPI
// processes over one. reference_fem::run_block_benchmark: a block of the lung material (k = 1, non-symmetric
// tangent) at n = 5, 8, 12, 16, 21 elements through its depth (16k to 1.1M DOFs), two time steps.
//   BM_FemBlock/amg/one_process/n      AMG, one process with two assembly threads
//   BM_FemBlock/direct/one_process/n   UMFPACK-preconditioned GMRES (the earlier solver), n <= 12
//   BM_FemBlock/amg/all_processes/n    AMG on every process of the job, one assembly thread each
// Time = assembly + linear solves of both steps (manual time); set-up and peak memory (summed over the
// processes) are counters.
//
// Run under `mpirun -np 2` to measure the distributed figures in the same run as the one-process ones: the
// one-process benchmarks then run on rank 0 while the other processes wait asleep.
#include <benchmark/benchmark.h>
#include <deal.II/base/mpi.h>

#include <chrono>
#include <memory>
#include <thread>

#include "benchmarks/mpi_benchmark_main.hpp"
#include "core/case.hpp"
#include "core/geometry.hpp"
#include "benchmarks/block_benchmark.hpp"
#include "reference_fem/fem_model.hpp"

namespace {

using reference_fem::LinearSolverType;

/// Wait for every process without spinning: a process that waits for a one-process run on rank 0 must not
/// take a core from it (MPI_Barrier polls).
void wait_for_all_processes() {
  MPI_Request request;
  MPI_Ibarrier(MPI_COMM_WORLD, &request);
  for (int done = 0; !done;) {
    MPI_Test(&request, &done, MPI_STATUS_IGNORE);
    if (!done) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

unsigned int cores() { return std::max(1u, std::thread::hardware_concurrency()); }

void BM_LungSmall(benchmark::State& state, LinearSolverType solver) {
  static std::unique_ptr<core::Case> c;
  static std::unique_ptr<core::Geometry> geometry;
  static Eigen::MatrixXd amg_samples;
  const bool root = dealii::Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0;
  if (root && !c) {  // Gmsh, once, outside the timed loop
    c = std::make_unique<core::Case>(core::load_case(std::string(TISSUE_SOURCE_DIR) + "/configs/lung_small.json"));
    core::GeometryOptions options;
    options.build_node_cloud = false;
    geometry = std::make_unique<core::Geometry>(core::build_geometry(*c, options));
  }
  reference_fem::FemRunResult result;
  for (auto _ : state) {
    if (root) {
      core::Case run = *c;
      run.fem.linear_solver = solver == LinearSolverType::direct ? "direct" : "amg";
      reference_fem::FemRunOptions options;
      options.communicator = MPI_COMM_SELF;
      options.threads = cores();
      result = reference_fem::run_case(run, *geometry, options);
    }
    wait_for_all_processes();
    state.SetIterationTime(result.total_seconds);
  }
  double assembly = 0.0, solve = 0.0;
  int newton = 0, gmres = 0;
  for (const auto& s : result.steps) {
    assembly += s.assembly_seconds;
    solve += s.solve_seconds;
    newton += s.newton_iterations;
    gmres += s.linear_iterations;
  }
  state.counters["dofs"] = static_cast<double>(result.n_dofs);
  state.counters["assembly_s"] = assembly;
  state.counters["linear_solve_s"] = solve;
  state.counters["newton_iterations"] = newton;
  state.counters["gmres_iterations"] = gmres;
  state.counters["peak_memory_MB"] = result.peak_memory_mb;
  if (solver == LinearSolverType::amg) {
    amg_samples = result.sample_displacements;
  } else if (amg_samples.size() == result.sample_displacements.size() && amg_samples.size() > 0) {
    state.counters["max_sample_difference_to_amg"] =
        (result.sample_displacements - amg_samples).cwiseAbs().maxCoeff() / amg_samples.cwiseAbs().maxCoeff();
  }
}

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
  // The node's cores: all threads for one process, shared among the processes of a distributed run.
  options.threads = all_processes ? std::max(1u, cores() / static_cast<unsigned int>(n_processes)) : cores();
  reference_fem::BlockBenchmarkResult result;
  for (auto _ : state) {
    if (all_processes || root) result = reference_fem::run_block_benchmark(options);
    wait_for_all_processes();
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
  for (const auto solver : {LinearSolverType::amg, LinearSolverType::direct})
    benchmark::RegisterBenchmark(solver == LinearSolverType::amg ? "BM_LungSmall/amg" : "BM_LungSmall/direct",
                                 BM_LungSmall, solver)
        ->UseManualTime()
        ->MeasureProcessCPUTime()
        ->Iterations(1)
        ->Unit(benchmark::kMillisecond);
  for (const int n : {5, 8, 12, 16, 21})
    benchmark::RegisterBenchmark("BM_FemBlock/amg/one_process", BM_FemBlock,
                                 LinearSolverType::amg, false)
        ->Arg(n)
        ->UseManualTime()
        ->MeasureProcessCPUTime()
        ->Iterations(1)
        ->Unit(benchmark::kMillisecond);
  for (const int n : {5, 8, 12})
    benchmark::RegisterBenchmark("BM_FemBlock/direct/one_process", BM_FemBlock,
                                 LinearSolverType::direct, false)
        ->Arg(n)
        ->UseManualTime()
        ->MeasureProcessCPUTime()
        ->Iterations(1)
        ->Unit(benchmark::kMillisecond);
  for (const int n : {5, 8, 12, 16, 21})
    benchmark::RegisterBenchmark("BM_FemBlock/amg/all_processes", BM_FemBlock,
                                 LinearSolverType::amg, true)
        ->Arg(n)
        ->UseManualTime()
        ->MeasureProcessCPUTime()
        ->Iterations(1)
        ->Unit(benchmark::kMillisecond);
  return bench::run_benchmarks_under_mpi(argc, argv);
}
