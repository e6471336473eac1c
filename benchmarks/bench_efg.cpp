// EFG model cost on box clouds of ~2k, 8k and 32k nodes (13^3, 20^3, 32^3; spacing 5 mm, d_max = 2, k = 6,
// quadrature order 2 on 6 tets per grid cell): one full assembly of eqs. 20-24 (material update, residual and
// tangent) and one linear solve (SparseLU factorisation + back substitution; 2k and 8k only: the 96k-DOF
// factorisation of the 32k cloud does not fit the time budget, see docs/PERFORMANCE.md).
// Cube clamped (penalty, eq. 23) on z = 0 and loaded by a shear traction on the top face; elastic step.
// Shape-function tabulation and sparsity are set-up work, timed separately in BM_EfgSetup.
#include <benchmark/benchmark.h>

#include <map>
#include <memory>

#include "meshless/box_mesh.hpp"
#include "meshless/efg_model.hpp"

namespace {

constexpr double kSpacing = 0.005;  // [m]

meshless::EfgProblem box_problem(int points_per_side) {
  const int cells = points_per_side - 1;
  const double edge = cells * kSpacing;
  auto tagger = [edge](const Eigen::Vector3d& c, const Eigen::Vector3d&) {
    if (c.z() < 1e-12) return core::FaceTag::fixed;
    if (c.z() > edge - 1e-12) return core::FaceTag::load;
    return core::FaceTag::free_surface;
  };
  meshless::EfgProblem p;
  p.name = "benchmark box";
  p.mesh = meshless::make_box_mesh(Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(edge), cells, cells, cells,
                                   tagger, 0.2, 3);
  p.material = {6000.0, 12000.0, 18000.0, 0.4, 0.0};
  p.support.d_max = 2.0;
  p.support.k = 6;
  p.quadrature_order = 2;
  p.node_spacing = kSpacing;
  p.penalty_factor = 1e3;
  p.traction = [](const Eigen::Vector3d&) { return Eigen::Vector3d(10.0, 0.0, 0.0); };
  p.step_times = {0.0};
  return p;
}

/// One set-up model per size, shared by the benchmarks (set-up of the 32k cloud takes tens of seconds).
meshless::EfgModel& model_for(int side) {
  static std::map<int, std::unique_ptr<meshless::EfgModel>> models;
  auto& m = models[side];
  if (!m) {
    m = std::make_unique<meshless::EfgModel>(box_problem(side));
    m->setup_system();
  }
  return *m;
}

void BM_EfgSetup(benchmark::State& state) {
  const int side = static_cast<int>(state.range(0));
  for (auto _ : state) {
    meshless::EfgModel model(box_problem(side));
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
}

void BM_EfgSolve(benchmark::State& state) {
  meshless::EfgModel& model = model_for(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    state.PauseTiming();
    model.assemble_system(true);  // invalidates the factorisation, so solve() factorises again
    state.ResumeTiming();
    model.solve();
  }
  state.counters["nodes"] = model.statistics().num_nodes;
  state.SetLabel(model.statistics().linear_solver);
}

}  // namespace

BENCHMARK(BM_EfgSetup)->Arg(13)->Arg(20)->Arg(32)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK(BM_EfgAssembly)->Arg(13)->Arg(20)->Arg(32)->Unit(benchmark::kSecond)->Iterations(2);
BENCHMARK(BM_EfgSolve)->Arg(13)->Arg(20)->Unit(benchmark::kSecond)->Iterations(1);

BENCHMARK_MAIN();
