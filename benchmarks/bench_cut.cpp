// The cost of cutting in the EFG model (paper §4, docs/MESHLESS.md §5): a full set-up of a cut cloud against the
// local update that advances its cut by one increment (EfgModel::advance_cut), on the sheared-box clouds of
// bench_efg (13^3, 20^3, 32^3 nodes, spacing 5 mm). The cut: two panels from the top face down a third of the box,
// across its middle; the update advances it from 80 % to 100 % of its length (one of five increments).
// Ratios within one run: full set-up / local update (the `speedup` counter of each local update, against a full
// set-up with the same cut timed just before it); how each grows with the node count.
//
// BM_CutLungFullSetUp / BM_CutLungLocalUpdate: the same on configs/lung_large.json at its shipped resolution (the
// built-in lung, its node cloud and its front transition) for a 10 mm extension of the incision: a full set-up with
// the whole cut against the local update from the cut 10 mm shorter. The geometry (Gmsh) is built once, untimed.
//
// BM_CutIncisionStep: that update followed by the re-solve of the time step it starts (one incision step of
// `tissue cut configs/lung_large.json`).
#include <benchmark/benchmark.h>

#include <chrono>
#include <memory>
#include <string>

#include "benchmarks/mpi_benchmark_main.hpp"
#include "core/case.hpp"
#include "core/geometry.hpp"
#include "meshless/efg/efg_model.hpp"
#include "meshless/efg/efg_problem.hpp"
#include "meshless/verification/verification_problems.hpp"

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

/// Wall time of a full set-up of `problem` [s]: measured beside each local update (with the timer paused), so
/// that the `speedup` counter is a ratio within one run.
double full_setup_seconds(meshless::EfgProblem problem) {
  const auto t0 = std::chrono::steady_clock::now();
  meshless::EfgModel model(std::move(problem));
  model.setup_system();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// The local update's counters: its phases, and the speed-up over the full set-up measured just before it.
void report_update(benchmark::State& state, const meshless::CutUpdate& update, double full_seconds) {
  state.counters["recomputed_fraction"] = static_cast<double>(update.volume_points_recomputed) / update.volume_points;
  state.counters["shape_s"] = update.shape_function_seconds;
  state.counters["quadrature_s"] = update.quadrature_seconds;
  state.counters["coupling_s"] = update.coupling_seconds;
  state.counters["pairs_added"] = static_cast<double>(update.pairs_added);
  state.counters["tables_packed"] = update.tables_packed ? 1.0 : 0.0;
  state.counters["update_s"] = update.seconds;
  state.counters["full_setup_s"] = full_seconds;
  state.counters["speedup"] = full_seconds / update.seconds;
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
    const double full_seconds = full_setup_seconds(cut_problem(side, cut));
    auto model = std::make_unique<meshless::EfgModel>(cut_problem(side, earlier));
    model->setup_system();
    state.ResumeTiming();
    const meshless::CutUpdate update = model->advance_cut(cut);
    report_update(state, update, full_seconds);
    state.PauseTiming();
    model.reset();
    state.ResumeTiming();
  }
  state.counters["nodes"] = side * side * side;
}

/// configs/lung_large.json as the EFG model's problem, with the whole cut (Gmsh once per process).
const meshless::EfgProblem& lung_large_problem() {
  static const meshless::EfgProblem problem = [] {
    const core::Case c = core::load_case(std::string(TISSUE_SOURCE_DIR) + "/configs/lung_large.json");
    core::GeometryOptions options;
    options.build_fem_mesh = false;
    return meshless::problem_from_case(c, core::build_geometry(c, options));
  }();
  return problem;
}

constexpr double kLungExtension = 0.010;  // [m] the issue's 10 mm advance of the incision

void BM_CutLungFullSetUp(benchmark::State& state) {
  lung_large_problem();  // Gmsh, outside the timed loop
  for (auto _ : state) {
    meshless::EfgModel model(lung_large_problem());
    model.setup_system();
    state.counters["shape_s"] = model.timings().shape_function_seconds;
    state.counters["nodes"] = model.statistics().num_nodes;
    state.counters["volume_points"] = model.statistics().num_volume_points;
  }
}

void BM_CutLungLocalUpdate(benchmark::State& state) {
  const core::RuledSurface cut = *lung_large_problem().cut;
  for (auto _ : state) {
    state.PauseTiming();
    const double full_seconds = full_setup_seconds(lung_large_problem());
    meshless::EfgProblem shorter = lung_large_problem();
    shorter.cut = cut.truncated(cut.trace_length() - kLungExtension);
    auto model = std::make_unique<meshless::EfgModel>(std::move(shorter));
    model->setup_system();
    state.ResumeTiming();
    const meshless::CutUpdate update = model->advance_cut(cut);
    report_update(state, update, full_seconds);
    state.counters["cut_length_mm"] = 1e3 * cut.trace_length();
    state.PauseTiming();
    model.reset();
    state.ResumeTiming();
  }
}

/// One step of a progressive incision at the shipped size (configs/lung_large.json, as `tissue cut` makes it): the
/// model with the incision 10 mm short solves time step 1 (untimed), then the timed part: the local update that
/// extends the incision by 10 mm (BM_CutLungLocalUpdate) and the re-solve of time step 2 (Newton with the history
/// carried over; the body changed, so its first tangent is factorised afresh).
void BM_CutIncisionStep(benchmark::State& state) {
  const core::RuledSurface cut = *lung_large_problem().cut;
  for (auto _ : state) {
    state.PauseTiming();
    meshless::EfgProblem shorter = lung_large_problem();
    shorter.cut = cut.truncated(cut.trace_length() - kLungExtension);
    auto model = std::make_unique<meshless::EfgModel>(std::move(shorter));
    model->setup_system();
    const meshless::StepRecord before = model->solve_step(1);
    state.ResumeTiming();
    const auto t0 = std::chrono::steady_clock::now();
    const meshless::CutUpdate update = model->advance_cut(cut);
    const meshless::StepRecord step = model->solve_step(2);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    state.PauseTiming();
    state.counters["update_s"] = update.seconds;
    state.counters["step_s"] = seconds;
    state.counters["assembly_s"] = step.assembly_seconds;
    state.counters["solve_s"] = step.solve_seconds;
    state.counters["newton_iterations"] = step.newton_iterations;
    state.counters["factorisations"] = step.factorisations;
    state.counters["gmres_iterations"] = step.linear_iterations;
    state.counters["pairs_added"] = static_cast<double>(update.pairs_added);
    state.counters["step1_s"] = before.assembly_seconds + before.solve_seconds;
    state.counters["step1_factorisations"] = before.factorisations;
    model.reset();
    state.ResumeTiming();
  }
}

}  // namespace

BENCHMARK(BM_CutFullSetUp)->Arg(13)->Arg(20)->Arg(32)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_CutLocalUpdate)->Arg(13)->Arg(20)->Arg(32)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_CutLungFullSetUp)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_CutLungLocalUpdate)->Unit(benchmark::kMillisecond)->Iterations(1);
// Minutes per run: not matched by the filter Lung.
BENCHMARK(BM_CutIncisionStep)->Unit(benchmark::kSecond)->Iterations(1);

int main(int argc, char** argv) {
  // A cloud too large to factorise gets the AMG-Krylov solver at set-up.
  return bench::run_benchmarks_with_petsc(argc, argv);
}
