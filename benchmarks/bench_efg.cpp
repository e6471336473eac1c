// EFG model cost on box clouds of ~2k, 8k and 32k nodes (13^3, 20^3, 32^3; spacing 5 mm, d_max = 2, k = 6,
// quadrature order 2 on 6 tets per grid cell): one full assembly of eqs. 20-24 (material update, residual and
// tangent) and one linear solve: the automatic choice (UMFPACK factorisation + back substitution when its
// estimated peak memory fits half the RAM, Jacobi-BiCGSTAB otherwise: the 32k cloud), and Jacobi-BiCGSTAB
// at the two smaller sizes for comparison (docs/PERFORMANCE.md).
// Cube clamped (penalty, eq. 23) on z = 0 and loaded by a shear traction on the top face; elastic step.
// Shape-function tabulation and sparsity are set-up work, timed separately in BM_EfgSetup.
#include <benchmark/benchmark.h>

#include <sys/resource.h>

#include <memory>

#include "meshless/efg_model.hpp"
#include "meshless/verification_problems.hpp"

namespace {

/// Peak resident memory of this process so far [GB]. The sizes run in increasing order, so after a 32k
/// benchmark this is the peak of the 32k model (set-up, assembly and, for the solve, the factorisation).
double peak_memory_gb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) * 1024.0 / 1e9;  // ru_maxrss is in KiB on Linux
}

/// One set-up model per size and solver, shared by the benchmarks (set-up of the 32k cloud takes tens of
/// seconds). Only one is kept alive at a time: the 32k model alone holds several GB.
meshless::EfgModel& model_for(int side, meshless::LinearSolverKind solver = meshless::LinearSolverKind::automatic) {
  static std::pair<int, meshless::LinearSolverKind> key{0, solver};
  static std::unique_ptr<meshless::EfgModel> model;
  if (!model || key != std::make_pair(side, solver)) {
    model.reset();
    meshless::EfgOptions options;
    options.linear_solver = solver;
    model = std::make_unique<meshless::EfgModel>(meshless::sheared_box_problem(side), options);
    model->setup_system();
    key = {side, solver};
  }
  return *model;
}

void BM_EfgSetup(benchmark::State& state) {
  const int side = static_cast<int>(state.range(0));
  for (auto _ : state) {
    meshless::EfgModel model(meshless::sheared_box_problem(side));
    model.setup_system();
    state.counters["shape_s"] = model.timings().shape_function_seconds;
  }
  state.counters["nodes"] = side * side * side;
}

void BM_EfgAssembly(benchmark::State& state) {
  meshless::EfgModel& model = model_for(static_cast<int>(state.range(0)));
  for (auto _ : state) model.assemble_system(true);
  state.counters["nodes"] = model.statistics().num_nodes;
  state.counters["nnz"] = static_cast<double>(model.statistics().matrix_nonzeros);
  state.counters["nodes_per_point"] = model.statistics().mean_nodes_per_point;
  state.counters["peak_rss_GB"] = peak_memory_gb();
}

/// One elastic load step (meshless::EfgModel::solve_step): Newton with one linear solve (UMFPACK factorisation
/// + back substitution, or Jacobi-BiCGSTAB) and two assemblies; the solve alone is the `solve_s` counter.
void time_solve(benchmark::State& state, meshless::LinearSolverKind solver) {
  meshless::EfgModel& model = model_for(static_cast<int>(state.range(0)), solver);
  meshless::StepRecord step;
  for (auto _ : state) step = model.solve_step(1);
  const meshless::EfgStatistics& st = model.statistics();
  state.counters["nodes"] = st.num_nodes;
  state.counters["solve_s"] = step.solve_seconds;
  state.counters["assembly_s"] = step.assembly_seconds;
  state.counters["newton_iterations"] = step.newton_iterations;
  state.counters["bicgstab_iterations"] = step.linear_iterations;
  state.counters["umfpack_peak_GB"] = st.direct_peak_memory_estimate / 1e9;
  state.counters["umfpack_Gflop"] = st.direct_flops_estimate / 1e9;
  state.counters["peak_rss_GB"] = peak_memory_gb();
  state.SetLabel(st.linear_solver);
}

void BM_EfgSolve(benchmark::State& state) { time_solve(state, meshless::LinearSolverKind::automatic); }
void BM_EfgSolveIterative(benchmark::State& state) { time_solve(state, meshless::LinearSolverKind::iterative); }

}  // namespace

BENCHMARK(BM_EfgSetup)->Arg(13)->Arg(20)->Arg(32)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK(BM_EfgAssembly)->Arg(13)->Arg(20)->Arg(32)->Unit(benchmark::kSecond)->Iterations(2);
BENCHMARK(BM_EfgSolve)->Arg(13)->Arg(20)->Arg(32)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK(BM_EfgSolveIterative)->Arg(13)->Arg(20)->Unit(benchmark::kSecond)->Iterations(1);

BENCHMARK_MAIN();
