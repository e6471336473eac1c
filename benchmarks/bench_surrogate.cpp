// The surrogate's real-time claim (paper §5.5, docs/SURROGATE.md §7, docs/PERFORMANCE.md):
//  * BM_SurrogateQuery/box and /shipped: one full-surface query (contact-node displacement from eqs. 25-27
//  and every
//    surface node's from eq. 28), with the per-query latency distribution (p50, p99, max) as counters; the
//    goal is p99 <= 50 us, 20x inside a 1 kHz haptic frame. `shipped` is the surrogate file named by the
//    environment variable TISSUE_SURROGATE (default results/surrogate/lung_surrogate.surrogate.json), skipped
//    when absent.
//  * BM_FullSolve/box and /shipped: what a query replaces, measured in the same run: the full meshless model
//  solving
//    one patch load up to the response step on a set-up model (EfgModel::restart + time steps +
//    interpolation). For `shipped` the case named in TISSUE_SURROGATE_CASE (default
//    configs/lung_surrogate.json) is meshed first.
//  * BM_SurrogateTraining/box: training + fitting of the box surrogate (tests/surrogate_box_case.hpp),
//  with the
//    file size.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <string>

#include "benchmarks/mpi_benchmark_main.hpp"
#include "core/case.hpp"
#include "core/geometry.hpp"
#include "meshless/efg/efg_model.hpp"
#include "meshless/surrogate/surrogate.hpp"
#include "tests/surrogate_box_case.hpp"
#include "meshless/surrogate/surrogate_builder.hpp"
#include "meshless/surrogate/surrogate_file.hpp"

namespace {

meshless::EfgProblem box_problem() { return meshless::surrogate_box_problem(); }

core::SurrogateSpec box_spec() {
  core::SurrogateSpec s = meshless::surrogate_box_spec();
  s.holdout_forces = 0;  // timed separately
  return s;
}

const meshless::SurrogateData& box_surrogate() {
  static const meshless::SurrogateData d = meshless::build_surrogate(box_problem(), box_spec(), {});
  return d;
}

std::string env_or(const char* name, const std::string& fallback) {
  const char* v = std::getenv(name);
  return v && *v ? v : fallback;
}

/// The shipped surrogate, or nullptr when its file is absent.
const meshless::Surrogate* shipped_surrogate() {
  static std::unique_ptr<meshless::Surrogate> s = []() -> std::unique_ptr<meshless::Surrogate> {
    const std::string path = env_or("TISSUE_SURROGATE", "results/surrogate/lung_surrogate.surrogate.json");
    if (!std::filesystem::exists(path)) return nullptr;
    return std::make_unique<meshless::Surrogate>(meshless::read_surrogate(path));
  }();
  return s.get();
}

/// Mean query time [s] of each surrogate, kept by its query benchmark for the full solve's ratio (the query
/// benchmarks are registered, so run, before the full solves).
std::map<std::string, double> mean_query_seconds;

/// Queries cycling over forces spread inside the trained range; per-query latencies as counters.
void time_queries(benchmark::State& state, const meshless::Surrogate& s, const std::string& name) {
  const Eigen::Vector3d x = s.data().surface_position.row(s.data().contacts[0].contact).transpose();
  const double f = s.data().max_force;
  std::vector<Eigen::Vector3d> forces;
  for (int i = 0; i < 64; ++i)
    forces.push_back(f * Eigen::Vector3d(std::sin(0.7 * i), std::cos(1.3 * i), std::sin(2.1 * i + 0.4)) /
                     1.8);
  core::PointMatrix u(s.num_surface_nodes(), 3);
  std::vector<double> latency;
  latency.reserve(1 << 20);
  std::size_t i = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    const meshless::SurrogateResponse r = s.query(x, forces[i++ % forces.size()], &u);
    benchmark::DoNotOptimize(r);
    benchmark::DoNotOptimize(u.data());
    if (latency.size() < latency.capacity())
      latency.push_back(
          std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
  }
  double sum = 0.0;
  for (double t : latency) sum += t;
  mean_query_seconds[name] = 1e-6 * sum / std::max<std::size_t>(1, latency.size());
  std::sort(latency.begin(), latency.end());
  auto at = [&](double p) {
    return latency[std::min(latency.size() - 1, static_cast<std::size_t>(p * latency.size()))];
  };
  state.counters["surface_nodes"] = s.num_surface_nodes();
  state.counters["p50_us"] = at(0.50);
  state.counters["p99_us"] = at(0.99);
  state.counters["max_us"] = latency.back();
}

/// One patch load on a set-up model, to the response step: what a query replaces.
void time_full_solve(benchmark::State& state, const meshless::EfgProblem& problem,
                     const meshless::SurrogateData& d, const std::string& name) {
  const meshless::SurfaceNodes surface = meshless::surface_nodes(problem.mesh);
  meshless::PatchSolveOptions options;
  options.patch_radius = d.patch_radius;
  options.response_step = meshless::response_step(problem, d.response_time == "end");
  options.max_workers = 1;
  // The contact by position: the cloud is rebuilt here, and its node numbering need not be the file's.
  const int contact = surface.nearest(d.surface_position.row(d.contacts[0].contact).transpose());
  const meshless::PatchLoad load{contact, {0.0, 0.0, -0.5 * d.max_force}};
  for (auto _ : state) {
    const std::vector<meshless::SolvedLoad> r =
        meshless::solve_patch_loads(problem, {}, surface, {load}, options);
    benchmark::DoNotOptimize(r);
    state.counters["solve_s"] = r[0].seconds;  // without the model's set-up
    state.counters["newton_iterations"] = r[0].newton_iterations;
    // What one query saves, measured in this run: the full solve over the mean query time.
    if (mean_query_seconds.count(name))
      state.counters["solve_over_query"] = r[0].seconds / mean_query_seconds[name];
  }
  state.counters["nodes"] = problem.mesh.num_vertices();
  state.counters["surface_nodes"] = surface.size();
}

void BM_SurrogateQuery_box(benchmark::State& state) {
  time_queries(state, meshless::Surrogate(box_surrogate()), "box");
}

void BM_FullSolve_box(benchmark::State& state) {
  time_full_solve(state, box_problem(), box_surrogate(), "box");
}

void BM_SurrogateQuery_shipped(benchmark::State& state) {
  const meshless::Surrogate* s = shipped_surrogate();
  if (!s) {
    state.SkipWithError(
        "no shipped surrogate file (run `tissue fit configs/lung_surrogate.json --out "
        "results/surrogate/lung_surrogate.surrogate.json` or set TISSUE_SURROGATE)");
    return;
  }
  time_queries(state, *s, "shipped");
}

void BM_FullSolve_shipped(benchmark::State& state) {
  const meshless::Surrogate* s = shipped_surrogate();
  if (!s) {
    state.SkipWithError("no shipped surrogate file");
    return;
  }
  const core::Case c = core::load_case(env_or("TISSUE_SURROGATE_CASE", "configs/lung_surrogate.json"));
  if (meshless::surrogate_case_hash(c) != s->data().case_hash) {
    state.SkipWithError("TISSUE_SURROGATE_CASE is not the case the shipped surrogate was fitted on");
    return;
  }
  core::GeometryOptions g;
  g.build_fem_mesh = false;
  const core::Geometry geometry = core::build_geometry(c, g);
  time_full_solve(state, meshless::problem_from_case(c, geometry), s->data(), "shipped");
}

void BM_SurrogateTraining_box(benchmark::State& state) {
  core::SurrogateSpec spec = box_spec();
  meshless::SurrogateBuildReport report;
  for (auto _ : state) {
    meshless::SurrogateData d = meshless::build_surrogate(box_problem(), spec, {}, {}, &report);
    const std::string path = (std::filesystem::temp_directory_path() / "bench_surrogate_box.json").string();
    meshless::write_surrogate(path, d);
    state.counters["file_kB"] = std::filesystem::file_size(path) / 1e3;
    std::filesystem::remove(path);
  }
  state.counters["solves"] = report.training_solves;
  state.counters["fit_s"] = report.fit_seconds;
  state.counters["training_solves_s"] = report.training.wall_seconds;
}

}  // namespace

BENCHMARK(BM_SurrogateQuery_box)->Unit(benchmark::kMicrosecond)->MinTime(2.0);
BENCHMARK(BM_FullSolve_box)->Unit(benchmark::kMillisecond)->Iterations(5);
BENCHMARK(BM_SurrogateTraining_box)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK(BM_SurrogateQuery_shipped)->Unit(benchmark::kMicrosecond)->MinTime(2.0);
BENCHMARK(BM_FullSolve_shipped)->Unit(benchmark::kSecond)->Iterations(1);

// MPI for the direct solver of the full solves (MUMPS, meshless/solvers/mumps_lu.hpp).
int main(int argc, char** argv) { return bench::run_benchmarks_with_petsc(argc, argv); }
