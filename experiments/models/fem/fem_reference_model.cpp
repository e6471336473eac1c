#include "experiments/models/fem/fem_reference_model.hpp"

#include <fmt/format.h>

namespace experiments {

ModelResult FemReferenceModel::solve(const core::Case& c, const core::Geometry& g, const SolveRequest& request) const {
  if (request.on_step)
    request.on_step(fmt::format("FEM reference: deal.II set-up ({} tets, degree {})", g.fem_mesh.num_tets(),
                                c.fem.degree));
  reference_fem::FemRunOptions options;
  options.communicator = MPI_COMM_SELF;
  options.vtu_prefix = request.vtu_prefix;
  options.on_step = [&](const reference_fem::StepReport& s) {
    if (request.on_step)
      request.on_step(fmt::format("FEM step {}/{} t = {:.3f} s: {} Newton iterations, residual {:.2e}", s.step,
                                  c.time.steps, s.time, s.newton_iterations, s.residuals.back()));
  };
  ModelResult r = fem_model_result(c, g, reference_fem::run_case(c, g, options), 0.0);
  r.details["geometry_seconds"] = nullptr;  // the geometry is shared; its time is the caller's
  return r;
}

ModelResult fem_model_result(const core::Case& c, const core::Geometry& g, const reference_fem::FemRunResult& f,
                             double setup) {
  ModelResult r;
  r.model = "fem";
  r.sample_points = g.sample_points;
  describe_samples_near_cut(g, &r);
  r.sample_displacements = f.sample_displacements;
  r.setup_seconds = setup + (f.sections.count("setup") ? f.sections.at("setup") : 0.0);
  r.total_seconds = setup + f.total_seconds;
  int builds = 0, tangent_assemblies = 0, residual_only_assemblies = 0;
  for (const auto& s : f.steps) {
    tangent_assemblies += s.tangent_assemblies;
    residual_only_assemblies += s.residual_only_assemblies;
    r.steps.push_back({s.step, s.time, s.wall_seconds, s.assembly_seconds, s.solve_seconds, s.newton_iterations,
                       s.residuals, s.linear_iterations, s.substeps, s.failed_attempts, s.admissibility_margin,
                       s.retried_plain});
    builds += s.preconditioner_builds;
  }
  r.details["preconditioner_builds"] = builds;
  r.details["tangent_assemblies"] = tangent_assemblies;
  r.details["residual_only_assemblies"] = residual_only_assemblies;
  r.details["linear_solver"] =
      c.fem.linear_solver == "direct"
          ? "GMRES (right-preconditioned by UMFPACK LU of an earlier consistent tangent)"
          : "GMRES (right-preconditioned by Trilinos ML smoothed-aggregation AMG of an earlier consistent tangent, "
            "rigid-body near null space)";
  r.details["mpi_processes"] = f.mpi_processes;
  r.details["cells_per_process"] = f.cells_per_process;
  r.details["peak_memory_mb"] = f.peak_memory_mb;
  r.details["n_dofs"] = f.n_dofs;
  r.details["n_cells"] = f.n_cells;
  r.details["load_area_mm2"] = f.load_area * 1e6;
  r.details["crack_faces"] = f.crack_faces;
  r.details["probe_strain"] = {{"measure", "largest absolute principal strain within the load radius of the load centre"},
                               {"mean", f.probe_strain.mean},
                               {"peak", f.probe_strain.peak}};
  r.details["law_admissibility"] = admissibility_json(f.smallest_margin, c.material);
  r.details["min_step_seconds"] = f.min_step;
  r.details["geometry_seconds"] = setup;
  r.details["timer_sections_seconds"] = f.sections;
  std::vector<double> offsets_mm;
  for (double o : f.sample_offsets) offsets_mm.push_back(o * 1e3);
  r.details["sample_offsets_mm"] = offsets_mm;
  return r;
}

}  // namespace experiments
