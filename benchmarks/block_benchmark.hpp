#pragma once
// The FEM scaling benchmark (docs/PERFORMANCE.md): a 100 x 20 x 20 mm block of the lung material of
// configs/lung_small.json (K1 = 6 kPa, K2 = 12 kPa, eta = 18 kPa s, nu = 0.4, k = 1: the tangent is
// non-symmetric), split into 5n x n x n hexahedra of 5 tetrahedra each, FE_SimplexP(2): about 122 n^3 DOFs
// (n = 5: 16k, n = 21: 1.1M). Clamped at x = 0 and pressed along -x on x = L by 300 Pa (about 5 % strain),
// stepped twice: the instantaneous response (t = 0) and one creep step (t = 0.2 s), 2-4 Newton iterations
// each. deal.II-free header.
#include <mpi.h>

#include <vector>

#include "reference_fem/problem.hpp"

namespace reference_fem {

struct BlockBenchmarkOptions {
  int subdivisions = 5;  ///< n: elements through the 20 mm depth
  MPI_Comm communicator = MPI_COMM_SELF;
  LinearSolverType linear_solver = LinearSolverType::amg;
  unsigned int threads = 0;  ///< assembly threads per process (0: deal.II's choice)
};

struct BlockBenchmarkResult {
  std::size_t n_dofs = 0;
  double setup_seconds = 0.0;  ///< mesh, partition, DoFs, sparsity, rigid-body modes
  std::vector<StepReport> steps;
  int newton_iterations = 0;
  double newton_seconds = 0.0;  ///< assembly + linear solves over both steps
  double seconds_per_newton_iteration = 0.0;
  double peak_memory_mb = 0.0;  ///< sum over the processes of their peak resident set during the call
};

/// Run the benchmark on the processes of options.communicator. Collective.
BlockBenchmarkResult run_block_benchmark(const BlockBenchmarkOptions& options);

}  // namespace reference_fem
