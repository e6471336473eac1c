#include "benchmarks/block_benchmark.hpp"

#include <deal.II/base/mpi.h>
#include <deal.II/base/utilities.h>
#include <deal.II/distributed/fully_distributed_tria.h>
#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/tria.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <memory>

#include "reference_fem/distributed_triangulation.hpp"
#include "reference_fem/viscoelastic_solver.hpp"

namespace reference_fem {
namespace {

using namespace dealii;

constexpr unsigned int kClamped = 1, kPressed = 2;
constexpr double kLength = 0.1, kDepth = 0.02;

/// Start the peak resident set size (VmHWM) afresh, so it measures this call (Linux >= 4.0).
void reset_peak_memory() { std::ofstream("/proc/self/clear_refs") << "5"; }

double peak_memory_mb(MPI_Comm communicator) {
  Utilities::System::MemoryStats stats;
  Utilities::System::get_memory_stats(stats);
  return Utilities::MPI::sum(static_cast<double>(stats.VmHWM) / 1024.0, communicator);
}

}  // namespace

BlockBenchmarkResult run_block_benchmark(const BlockBenchmarkOptions& options) {
  reset_peak_memory();
  const auto start = std::chrono::steady_clock::now();
  const unsigned int n = static_cast<unsigned int>(options.subdivisions);
  auto whole = std::make_unique<Triangulation<3>>();
  GridGenerator::subdivided_hyper_rectangle_with_simplices(*whole, {5 * n, n, n}, Point<3>(0, 0, 0),
                                                          Point<3>(kLength, kDepth, kDepth));
  for (const auto& cell : whole->active_cell_iterators())
    for (const auto f : cell->face_indices())
      if (cell->face(f)->at_boundary()) {
        const double x = cell->face(f)->center()[0];
        if (x < 1e-9) cell->face(f)->set_boundary_id(kClamped);
        if (x > kLength - 1e-9) cell->face(f)->set_boundary_id(kPressed);
      }
  parallel::fullydistributed::Triangulation<3> triangulation(options.communicator);
  distribute_triangulation(whole.get(), &triangulation);
  whole.reset();

  SolverParameters parameters;
  parameters.material.K1 = 6000.0;
  parameters.material.K2 = 12000.0;
  parameters.material.eta = 18000.0;
  parameters.material.nu = 0.4;
  parameters.material.k = 1.0;
  parameters.degree = 2;
  parameters.newton.linear = LinearSolverParameters::for_type(options.linear_solver);
  parameters.threads = options.threads;
  BoundaryConditions conditions;
  DirichletCondition clamp;
  clamp.boundary_id = kClamped;
  conditions.dirichlet.push_back(clamp);
  TractionCondition press;
  press.boundary_id = kPressed;
  press.traction = Eigen::Vector3d(-300.0, 0.0, 0.0);
  conditions.tractions.push_back(press);

  ViscoelasticSolver solver(triangulation, parameters, conditions);
  solver.setup_system();
  BlockBenchmarkResult result;
  result.n_dofs = solver.dof_handler().n_dofs();
  result.setup_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  solver.run({0.0, 0.2}, [&](const StepReport& report) {
    result.steps.push_back(report);
    result.newton_iterations += report.newton_iterations;
    result.newton_seconds += report.assembly_seconds + report.solve_seconds;
  });
  result.seconds_per_newton_iteration = result.newton_seconds / std::max(1, result.newton_iterations);
  result.peak_memory_mb = peak_memory_mb(options.communicator);
  return result;
}

}  // namespace reference_fem
