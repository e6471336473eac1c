#include "reference_fem/fem_model.hpp"

#include <deal.II/grid/tria.h>
#include <fmt/format.h>

#include <chrono>

#include "core/load_program.hpp"

#include "reference_fem/sample_evaluator.hpp"
#include "reference_fem/triangulation_from_mesh.hpp"
#include "reference_fem/viscoelastic_solver.hpp"

namespace reference_fem {

FemRunResult solve_on_mesh(const core::TetMesh& mesh, const SolverParameters& parameters,
                           const BoundaryConditions& conditions, const std::vector<double>& times,
                           const Eigen::MatrixXd& sample_points, const FemRunOptions& options, int output_every) {
  const auto start = std::chrono::steady_clock::now();
  dealii::Triangulation<3> triangulation;
  build_triangulation(mesh, &triangulation);

  SolverParameters p = parameters;
  p.threads = options.threads;
  ViscoelasticSolver solver(triangulation, p, conditions);
  solver.setup_system();
  const SampleEvaluator samples(solver.mapping(), solver.dof_handler(), sample_points, options.sample_tolerance,
                                options.cut);

  FemRunResult result;
  result.n_dofs = solver.dof_handler().n_dofs();
  result.n_cells = triangulation.n_active_cells();
  result.sample_offsets = samples.offsets();
  const int every = std::max(1, output_every);
  const int n_steps = static_cast<int>(times.size());
  solver.run(times, [&](const StepReport& report) {
    result.steps.push_back(report);
    result.sample_history.push_back(samples.evaluate(solver.solution()));
    if (!options.vtu_prefix.empty() && (report.step % every == 0 || report.step == n_steps)) {
      const std::string file = fmt::format("{}_{:04d}.vtu", options.vtu_prefix, report.step);
      solver.output_results(file);
      result.vtu_files.push_back(file);
    }
    if (options.on_step) options.on_step(report);
  });
  result.sample_displacements =
      result.sample_history.empty() ? Eigen::MatrixXd::Zero(sample_points.rows(), 3) : result.sample_history.back();
  result.vertex_displacements = vertex_displacements(solver.dof_handler(), solver.solution());
  if (options.probe_radius > 0.0) result.probe_strain = solver.strain_in_ball(options.probe_centre, options.probe_radius);
  result.sections = solver.section_seconds();
  result.total_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

FemRunResult run_case(const core::Case& c, const core::Geometry& geometry, const FemRunOptions& options) {
  const core::LoadProgram program = core::load_program(c, geometry.fem_mesh);
  BoundaryConditions bc;
  bc.dirichlet.push_back(DirichletCondition{});  // the fixed region: u = 0 on every component (strong)
  TractionCondition load;
  load.boundary_id = boundary_id::load;
  load.traction = program.traction;
  load.scale = [program](double t) { return program.scale(t); };
  bc.tractions.push_back(load);

  SolverParameters parameters;
  parameters.material = c.material;
  parameters.degree = c.fem.degree;
  parameters.newton.tolerance = c.fem.newton_tolerance;
  parameters.newton.max_iterations = c.fem.max_newton_iterations;

  FemRunOptions run = options;
  if (!run.cut && geometry.cut) run.cut = &*geometry.cut;
  if (!(run.probe_radius > 0.0)) {
    run.probe_centre = geometry.load_centre;
    run.probe_radius = c.load.radius;
  }
  FemRunResult result =
      solve_on_mesh(geometry.fem_mesh, parameters, bc, program.step_times, geometry.sample_points, run, c.output.every);
  result.load_area = program.patch_area;
  for (const auto tag : geometry.fem_mesh.face_tags) result.crack_faces += tag == core::FaceTag::crack;
  return result;
}

}  // namespace reference_fem
