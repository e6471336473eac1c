#include "reference_fem/fem_model.hpp"

#include <deal.II/base/mpi.h>
#include <deal.II/base/utilities.h>
#include <deal.II/distributed/fully_distributed_tria.h>
#include <deal.II/grid/tria.h>
#include <fmt/format.h>

#include <chrono>
#include <filesystem>

#include "core/load_program.hpp"
#include "reference_fem/distributed_triangulation.hpp"
#include "reference_fem/sample_evaluator.hpp"
#include "reference_fem/triangulation_from_mesh.hpp"
#include "reference_fem/viscoelastic_solver.hpp"

namespace reference_fem {

FemRunResult solve_on_mesh(const core::TetMesh& mesh, const SolverParameters& parameters,
                           const BoundaryConditions& conditions, const std::vector<double>& times,
                           const Eigen::MatrixXd& sample_points, const FemRunOptions& options, int output_every) {
  const auto start = std::chrono::steady_clock::now();
  // The whole mesh is needed only to partition it and to locate the samples; it is freed before stepping.
  auto whole = std::make_unique<dealii::Triangulation<3>>();
  build_triangulation(mesh, whole.get());
  dealii::parallel::fullydistributed::Triangulation<3> triangulation(options.communicator);
  distribute_triangulation(whole.get(), &triangulation);

  SolverParameters p = parameters;
  p.threads = options.threads;
  ViscoelasticSolver solver(triangulation, p, conditions);
  solver.setup_system();
  const SampleEvaluator samples(solver.mapping(), *whole, solver.dof_handler(), sample_points,
                                options.sample_tolerance, options.cut);
  whole.reset();

  FemRunResult result;
  result.n_dofs = solver.dof_handler().n_dofs();
  result.n_cells = triangulation.n_global_active_cells();
  result.mpi_processes = static_cast<int>(dealii::Utilities::MPI::n_mpi_processes(options.communicator));
  result.cells_per_process =
      dealii::Utilities::MPI::all_gather(options.communicator, triangulation.n_locally_owned_active_cells());
  result.sample_offsets = samples.offsets();
  const int every = std::max(1, output_every);
  const int n_steps = static_cast<int>(times.size());
  const std::filesystem::path prefix(options.vtu_prefix);
  solver.run(times, [&](const StepReport& report) {
    result.steps.push_back(report);
    result.sample_history.push_back(samples.evaluate(solver.solution()));
    if (!options.vtu_prefix.empty() && (report.step % every == 0 || report.step == n_steps))
      result.vtu_files.push_back(solver.output_results(prefix.parent_path().string(), prefix.filename().string(),
                                                       static_cast<unsigned int>(report.step)));
    if (options.on_step) options.on_step(report);
  });
  result.sample_displacements =
      result.sample_history.empty() ? Eigen::MatrixXd::Zero(sample_points.rows(), 3) : result.sample_history.back();
  result.vertex_displacements = vertex_displacements(solver.dof_handler(), solver.solution(), mesh);
  if (options.probe_radius > 0.0) result.probe_strain = solver.strain_in_ball(options.probe_centre, options.probe_radius);
  if (options.support_region) {
    const core::FixedRegionSpec region = *options.support_region;
    result.support_edge_strain =
        solver.strain_where([&](const Eigen::Vector3d& x) { return std::abs(region.depth_inside(x)) <= kSupportEdgeBand; });
  }
  result.smallest_margin = solver.smallest_margin();
  result.min_step = parameters.newton.min_step;
  result.sections = solver.section_seconds();
  dealii::Utilities::System::MemoryStats memory;
  dealii::Utilities::System::get_memory_stats(memory);
  result.peak_memory_mb = dealii::Utilities::MPI::sum(static_cast<double>(memory.VmHWM) / 1024.0, options.communicator);
  result.total_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

CaseProblem problem_from_case(const core::Case& c, const core::TetMesh& mesh) {
  const core::LoadProgram program = core::load_program(c, mesh);
  CaseProblem problem;
  if (c.fixed_region.support == core::FixedRegionSpec::Support::clamp) {
    problem.conditions.dirichlet.push_back(DirichletCondition{});  // the fixed region: u = 0 on every component
  } else {
    ElasticSupportCondition support;  // the fixed region: t = -k_s(x) u, k_s as the case defines it
    const core::FixedRegionSpec region = c.fixed_region;
    support.stiffness = [region](const Eigen::Vector3d& x) { return region.support_stiffness(x); };
    problem.conditions.supports.push_back(support);
  }
  TractionCondition load;
  load.boundary_id = boundary_id::load;
  load.traction = program.traction;
  load.scale = [program](double t) { return program.scale(t); };
  problem.conditions.tractions.push_back(load);

  SolverParameters& parameters = problem.parameters;
  parameters.material = c.material;
  parameters.degree = c.fem.degree;
  parameters.newton.tolerance = c.fem.newton_tolerance;
  parameters.newton.max_iterations = c.fem.max_newton_iterations;
  parameters.newton.min_step = program.min_step;
  parameters.newton.linear = LinearSolverParameters::for_type(
      c.fem.linear_solver == "direct" ? LinearSolverType::direct : LinearSolverType::amg);
  problem.times = program.step_times;
  problem.load_area = program.patch_area;
  return problem;
}

FemRunResult run_case(const core::Case& c, const core::Geometry& geometry, const FemRunOptions& options) {
  const CaseProblem problem = problem_from_case(c, geometry.fem_mesh);
  FemRunOptions run = options;
  if (!run.cut && geometry.cut) run.cut = &*geometry.cut;
  if (!run.support_region) run.support_region = &c.fixed_region;
  if (!(run.probe_radius > 0.0)) {
    run.probe_centre = geometry.load_centre;
    run.probe_radius = c.load.radius;
  }
  FemRunResult result = solve_on_mesh(geometry.fem_mesh, problem.parameters, problem.conditions, problem.times,
                                      geometry.sample_points, run, c.output.every);
  result.load_area = problem.load_area;
  for (const auto tag : geometry.fem_mesh.face_tags) result.crack_faces += tag == core::FaceTag::crack;
  return result;
}

}  // namespace reference_fem
