// Throughput of MLS shape-function evaluation (paper eqs. 1-8) on jittered-grid clouds of ~2k, 8k and 32k
// nodes with the default support radii (d_max = 2, k = 8), and of the LRPIM's RPIM shape functions (the 20 nearest
// nodes, meshless/lrpim/rpim_shape_functions.hpp) on the 8k-node cloud: the LRPIM's set-up evaluates them at every
// integration point (docs/PERFORMANCE.md, "Where a lung case's time goes, one thread").
// items_per_second = evaluation points per second.
#include <benchmark/benchmark.h>

#include <memory>
#include <random>
#include <vector>

#include "meshless/lrpim/rpim_shape_functions.hpp"
#include "meshless/mls/mls_shape_functions.hpp"
#include "meshless/mls/node_search.hpp"
#include "meshless/mls/support_radii.hpp"

namespace {

using meshless::MlsEvaluation;

/// n^3 nodes at spacing 0.01 m, each coordinate jittered by U(-0.3, 0.3) spacings, plus query points inside.
struct Fixture {
  explicit Fixture(int n)
      : nodes(make_nodes(n)), search(nodes), radii(nodes, search), mls(nodes, radii, search) {
    std::mt19937 gen(7);
    std::uniform_real_distribution<double> u(0.0, (n - 1) * kSpacing);
    points.resize(4096);
    for (auto& x : points) x = Eigen::Vector3d(u(gen), u(gen), u(gen));
  }
  static core::PointMatrix make_nodes(int n) {
    std::mt19937 gen(2024);
    std::uniform_real_distribution<double> u(-0.3 * kSpacing, 0.3 * kSpacing);
    core::PointMatrix p(n * n * n, 3);
    int row = 0;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        for (int k = 0; k < n; ++k, ++row)
          p.row(row) << i * kSpacing + u(gen), j * kSpacing + u(gen), k * kSpacing + u(gen);
    return p;
  }
  static constexpr double kSpacing = 0.01;  // [m]
  core::PointMatrix nodes;
  meshless::NodeSearch search;
  meshless::SupportRadii radii;
  meshless::MlsShapeFunctions mls;
  std::vector<Eigen::Vector3d> points;
};

/// One fixture per cloud size, built once (the KD-tree and radii are not what is timed here).
Fixture& fixture(int n) {
  static std::unique_ptr<Fixture> cache[64];
  if (!cache[n]) cache[n] = std::make_unique<Fixture>(n);
  return *cache[n];
}

void run(benchmark::State& state, bool with_gradients) {
  Fixture& f = fixture(static_cast<int>(state.range(0)));
  MlsEvaluation ev;
  size_t i = 0;
  double neighbours = 0;
  for (auto _ : state) {
    f.mls.evaluate(f.points[i++ % f.points.size()], with_gradients, &ev);
    neighbours += ev.size();
    benchmark::DoNotOptimize(ev.phi.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["nodes"] = static_cast<double>(f.nodes.rows());
  state.counters["mean_support"] = neighbours / static_cast<double>(state.iterations());
}

void run_rpim(benchmark::State& state, bool with_gradients) {
  Fixture& f = fixture(static_cast<int>(state.range(0)));
  const meshless::lrpim::RpimShapeFunctions rpim(f.nodes, f.search, Fixture::kSpacing);
  meshless::lrpim::RpimEvaluation ev;
  size_t i = 0;
  for (auto _ : state) {
    rpim.evaluate(f.points[i++ % f.points.size()], with_gradients, &ev);
    benchmark::DoNotOptimize(ev.phi.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["nodes"] = static_cast<double>(f.nodes.rows());
}

void BM_MlsValues(benchmark::State& state) { run(state, false); }
void BM_MlsValuesAndGradients(benchmark::State& state) { run(state, true); }

// 13^3 = 2197, 20^3 = 8000, 32^3 = 32768 nodes.
BENCHMARK(BM_MlsValues)->Arg(13)->Arg(20)->Arg(32)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_MlsValuesAndGradients)->Arg(13)->Arg(20)->Arg(32)->Unit(benchmark::kMicrosecond);

void BM_RpimValues(benchmark::State& state) { run_rpim(state, false); }
void BM_RpimValuesAndGradients(benchmark::State& state) { run_rpim(state, true); }
BENCHMARK(BM_RpimValues)->Arg(20)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_RpimValuesAndGradients)->Arg(20)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
