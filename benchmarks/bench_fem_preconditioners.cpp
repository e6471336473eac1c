// Which preconditioner for the FEM reference's Newton systems (docs/FEM_REFERENCE.md, "The linear solver";
// docs/PERFORMANCE.md). The first Newton system of lung_small (configs/lung_small.json: k = 1, so the tangent
// is non-symmetric) at 12 mm, solved by right-preconditioned GMRES(60) to 1e-10 relative residual with every
// candidate of reference_fem::compare_preconditioners: Trilinos ML variants, PETSc GAMG, hypre BoomerAMG,
// UMFPACK LU. Time = preconditioner set-up + solve (manual time); counters split them, in wall and in CPU time
// (the latter is the fairer measure on a loaded machine).
//   build/bin/bench_fem_preconditioners                         (one process)
//   mpirun -np 2 build/bin/bench_fem_preconditioners            (both, distributed; no UMFPACK)
// Set TISSUE_BENCH_MESH_MM to change the mesh size.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <map>
#include <memory>

#include "benchmarks/mpi_benchmark_main.hpp"
#include "core/case.hpp"
#include "core/geometry.hpp"
#include "reference_fem/fem_model.hpp"
#include "core/geometry_broadcast.hpp"
#include "benchmarks/preconditioner_study.hpp"

namespace {

struct LungSystem {
  core::Case c;
  core::Geometry geometry;
  reference_fem::CaseProblem problem;
};

const LungSystem& lung_small() {
  static std::unique_ptr<LungSystem> system;
  if (!system) {
    system = std::make_unique<LungSystem>();
    system->c = core::load_case(std::string(TISSUE_SOURCE_DIR) + "/configs/lung_small.json");
    const char* size = std::getenv("TISSUE_BENCH_MESH_MM");
    core::GeometryOptions options;
    options.build_node_cloud = false;
    options.fem_mesh_size = (size ? std::atof(size) : 12.0) * 1e-3;
    system->geometry = core::build_on_rank_zero(
        [&] { return core::build_geometry(system->c, options); }, MPI_COMM_WORLD);
    system->problem = reference_fem::problem_from_case(system->c, system->geometry.fem_mesh);
  }
  return *system;
}

void BM_LungFirstNewtonSystem(benchmark::State& state, const std::string& candidate) {
  const LungSystem& lung = lung_small();
  reference_fem::PreconditionerStudy study;
  for (auto _ : state) {
    study = reference_fem::compare_preconditioners(lung.geometry.fem_mesh, lung.problem.parameters,
                                                   lung.problem.conditions, lung.problem.times.front(), 1e-10,
                                                   MPI_COMM_WORLD, {candidate});
    if (study.trials.empty()) {
      state.SkipWithError("not available with this process count");
      return;
    }
    state.SetIterationTime(study.trials[0].setup_seconds + study.trials[0].solve_seconds);
  }
  const reference_fem::PreconditionerTrial& t = study.trials[0];
  state.counters["dofs"] = static_cast<double>(study.n_dofs);
  state.counters["setup_s"] = t.setup_seconds;
  state.counters["solve_s"] = t.solve_seconds;
  state.counters["setup_cpu_s"] = t.setup_cpu_seconds;
  state.counters["solve_cpu_s"] = t.solve_cpu_seconds;
  state.counters["iterations"] = t.iterations;
  state.counters["converged"] = t.converged ? 1 : 0;
  state.counters["relative_residual"] = t.relative_residual;
  state.counters["assembly_s"] = study.assembly_seconds;
}

}  // namespace

int main(int argc, char** argv) {
  for (const std::string& name : reference_fem::preconditioner_candidates())
    benchmark::RegisterBenchmark(("BM_LungFirstNewtonSystem/" + name).c_str(), BM_LungFirstNewtonSystem, name)
        ->UseManualTime()
        ->Iterations(1)
        ->Unit(benchmark::kMillisecond);
  return bench::run_benchmarks_under_mpi(argc, argv);
}
