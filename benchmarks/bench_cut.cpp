// The cost of cutting in the EFG model (paper §4, docs/MESHLESS.md §5): a full set-up of a cut cloud against the
// local update that advances its cut by one increment (EfgModel::advance_cut), on the sheared-box clouds of
// bench_efg (13^3, 20^3, 32^3 nodes, spacing 5 mm). The cut: two panels from the top face down a third of the box,
// across its middle; the update advances it from 80 % to 100 % of its length (one of five increments).
// Ratios within one run: full set-up / local update; how each grows with the node count.
#include <benchmark/benchmark.h>

#include <memory>

#include "benchmarks/mpi_benchmark_main.hpp"
#include "meshless/efg_model.hpp"
#include "meshless/verification_problems.hpp"

namespace {

core::RuledSurface box_cut(int side) {
  const double edge = 0.005 * (side - 1), top = edge;
  return core::RuledSurface({Eigen::Vector3d(0.15 * edge, 0.52 * edge, top), Eigen::Vector3d(0.5 * edge, 0.45 * edge, top),
                             Eigen::Vector3d(0.85 * edge, 0.55 * edge, top)},
                            -Eigen::Vector3d::UnitZ(), edge / 3.0);
}

meshless::EfgProblem cut_problem(int side, const core::RuledSurface& cut) {
  meshless::EfgProblem p = meshless::sheared_box_problem(side);
  p.cut = cut;
  p.cut_treatment = meshless::CutTreatment::enrichment;
  p.front_transition = 0.02 * p.node_spacing;
  return p;
}

void BM_CutFullSetUp(benchmark::State& state) {
  const int side = static_cast<int>(state.range(0));
  const core::RuledSurface cut = box_cut(side);
  for (auto _ : state) {
    meshless::EfgModel model(cut_problem(side, cut));
    model.setup_system();
    state.counters["shape_s"] = model.timings().shape_function_seconds;
    state.counters["lip_points"] = model.statistics().num_lip_points;
  }
  state.counters["nodes"] = side * side * side;
}

void BM_CutLocalUpdate(benchmark::State& state) {
  const int side = static_cast<int>(state.range(0));
  const core::RuledSurface cut = box_cut(side);
  const core::RuledSurface earlier = cut.truncated(0.8 * cut.trace_length());
  for (auto _ : state) {
    state.PauseTiming();
    auto model = std::make_unique<meshless::EfgModel>(cut_problem(side, earlier));
    model->setup_system();
    state.ResumeTiming();
    const meshless::CutUpdate update = model->advance_cut(cut);
    state.counters["recomputed_fraction"] =
        static_cast<double>(update.volume_points_recomputed) / update.volume_points;
    state.counters["shape_s"] = update.shape_function_seconds;
    state.counters["quadrature_s"] = update.quadrature_seconds;
    state.counters["coupling_s"] = update.coupling_seconds;
    state.counters["pairs_added"] = static_cast<double>(update.pairs_added);
    state.PauseTiming();
    model.reset();
    state.ResumeTiming();
  }
  state.counters["nodes"] = side * side * side;
}

}  // namespace

BENCHMARK(BM_CutFullSetUp)->Arg(13)->Arg(20)->Arg(32)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_CutLocalUpdate)->Arg(13)->Arg(20)->Arg(32)->Unit(benchmark::kMillisecond)->Iterations(1);

int main(int argc, char** argv) {
  // A cloud too large to factorise gets the AMG-Krylov solver at set-up.
  return bench::run_benchmarks_with_petsc(argc, argv);
}
