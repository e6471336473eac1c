// FEM reference: setup + assembly + solve time against the number of DOFs (docs/PERFORMANCE.md,
// "FEM reference"). One instantaneous (dt = 0) Newton step of the Timoshenko cantilever at degree 2:
// two WorkStream assemblies of the consistent tangent and one UMFPACK-preconditioned solve.
#include <benchmark/benchmark.h>

#include "reference_fem/verification.hpp"

namespace {

void BM_FemCantileverStep(benchmark::State& state) {
  reference_fem::CantileverOptions options;
  options.degree = 2;
  reference_fem::CantileverLevel level;
  for (auto _ : state) {
    level = reference_fem::run_cantilever(options, static_cast<int>(state.range(0)));
    benchmark::DoNotOptimize(level.l2_error);
  }
  state.counters["dofs"] = static_cast<double>(level.n_dofs);
  state.counters["dofs_per_s"] =
      benchmark::Counter(static_cast<double>(level.n_dofs) * state.iterations(), benchmark::Counter::kIsRate);
}

// Elements through the depth (5x along the length): about 1.5k, 9k, 28k and 63k DOFs.
BENCHMARK(BM_FemCantileverStep)->Arg(2)->Arg(4)->Arg(6)->Arg(8)->Unit(benchmark::kMillisecond)->Iterations(2);

}  // namespace

BENCHMARK_MAIN();
