#include "experiments/commands/solve_commands.hpp"

#include <deal.II/base/mpi.h>
#include <fmt/format.h>

#include <stdexcept>

#include <iostream>
#include <deque>
#include <memory>

#include "core/case.hpp"
#include "core/geometry.hpp"
#include "core/output_directory.hpp"
#include "experiments/models/efg/meshless_runs.hpp"
#include "experiments/models/model_result.hpp"
#include "experiments/models/model_registry.hpp"
#include "experiments/models/fem/fem_reference_model.hpp"
#include "experiments/io/progress.hpp"
#include "experiments/io/rank_zero_output.hpp"
#include "reference_fem/fem_model.hpp"
#include "core/geometry_broadcast.hpp"

namespace experiments {
namespace {

/// Every solver writes the same files: samples.csv, timings.json and the config as run.
void write_model_files(const core::OutputDirectory& out, const core::Case& c, const ModelResult& r) {
  write_samples_csv(out.file("samples.csv").string(), r);
  write_timings_json(out.file("timings.json").string(), r);
  write_text_file(out.file("case.json").string(), c.document.dump(2) + "\n");
}

void print_summary(const ModelResult& r) {
  double max_u = 0.0;
  for (Eigen::Index i = 0; i < r.sample_displacements.rows(); ++i)
    max_u = std::max(max_u, r.sample_displacements.row(i).norm());
  int iterations = 0;
  for (const auto& s : r.steps) iterations += s.iterations;
  std::cout << fmt::format("{}: {} steps, {} Newton iterations, max sample displacement {:.4f} mm, {:.1f} s\n",
                           r.model, r.steps.size(), iterations, max_u * 1e3, r.total_seconds);
}

/// The case's geometry with one of its two discretisations, timed (the set-up cost of the model).
core::Geometry build_timed_geometry(const core::Case& c, bool fem, Progress* progress, double* seconds) {
  progress->step(fem ? "building geometry and the FEM mesh (Gmsh)" : "building geometry and the node cloud (Gmsh)");
  core::GeometryOptions options;
  options.build_fem_mesh = fem;
  options.build_node_cloud = !fem;
  const double t0 = progress->elapsed_seconds();
  core::Geometry g = core::build_geometry(c, options);
  *seconds = progress->elapsed_seconds() - t0;
  return g;
}

int run_solve_fem(const std::string& config, const std::string& out_dir) {
  // Under mpirun every process runs this function: rank 0 meshes, prints and writes the results files, all
  // of them solve together (reference_fem/fem_model.hpp).
  const bool root = dealii::Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0;
  const unsigned int n_processes = dealii::Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD);
  const core::Case c = core::load_case(config);
  Progress progress("solve fem", 2 + c.time.steps, !root);
  std::string staging;
  // Staged: nothing is left behind if anything below fails.
  const std::unique_ptr<core::OutputDirectory> out = stage_on_rank_zero(out_dir, &staging);
  double geometry_seconds = 0.0;
  const core::Geometry g = core::build_on_rank_zero(
      [&] { return build_timed_geometry(c, true, &progress, &geometry_seconds); }, MPI_COMM_WORLD);
  progress.step(fmt::format("deal.II setup and time stepping ({} tets, degree {}, {} linear solver, {} MPI process{})",
                            g.fem_mesh.num_tets(), c.fem.degree, c.fem.linear_solver, n_processes,
                            n_processes > 1 ? "es" : ""));
  reference_fem::FemRunOptions run;
  run.communicator = MPI_COMM_WORLD;
  if (c.output.vtu) run.vtu_prefix = staging + "/displacement";
  run.on_step = [&](const reference_fem::StepReport& s) {
    progress.step(fmt::format("step {}/{} t = {:.3f} s: {} Newton iterations ({} GMRES, {} preconditioner build{}), "
                              "residual {:.2e}{}",
                              s.step, c.time.steps, s.time, s.newton_iterations, s.linear_iterations,
                              s.preconditioner_builds, s.preconditioner_builds == 1 ? "" : "s", s.residuals.back(),
                              s.failed_attempts.empty() ? std::string()
                                                        : fmt::format(", {} cut-backs into {} sub-steps",
                                                                      s.failed_attempts.size(), s.substeps)));
  };
  const reference_fem::FemRunResult f = reference_fem::run_case(c, g, run);
  if (!root) return 0;  // rank 0 writes the results files
  const ModelResult r = fem_model_result(c, g, f, geometry_seconds);
  write_model_files(*out, c, r);
  out->commit();
  progress.done();
  print_summary(r);
  std::cout << fmt::format("strain under the probe (largest |principal|): mean {:.2f} %, peak {:.2f} %\n",
                           f.probe_strain.mean * 100, f.probe_strain.peak * 100);
  std::cout << fmt::format("wrote {}\n", out->destination().string());
  return 0;
}

/// The end of `solve meshless` and `cut`: the geometry's time counted as set-up, the samples' distances to the cut,
/// the files written and committed, the summary printed.
int finish_meshless_run(const core::Case& c, const core::Geometry& g, double geometry_seconds, ModelResult* r,
                        core::OutputDirectory* out, Progress* progress) {
  r->details["geometry_seconds"] = geometry_seconds;
  describe_samples_near_cut(g, r);
  r->setup_seconds += geometry_seconds;
  r->total_seconds += geometry_seconds;
  write_model_files(*out, c, *r);
  out->commit();
  progress->done();
  print_summary(*r);
  std::cout << fmt::format("wrote {}\n", out->destination().string());
  return 0;
}

int run_solve_meshless(const std::string& config, const std::string& out_dir) {
  // Under mpirun every process runs this function: rank 0 meshes, prints and writes the results files; all build
  // the same EFG model from rank 0's geometry and share its Krylov solves (meshless/solvers/petsc_krylov_solver.hpp).
  const bool root = dealii::Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0;
  const core::Case c = core::load_case(config);
  Progress progress("solve meshless", 3 + c.time.steps, !root);
  std::string staging;
  // Staged: nothing is left behind if anything below fails.
  const std::unique_ptr<core::OutputDirectory> out = stage_on_rank_zero(out_dir, &staging);
  double geometry_seconds = 0.0;
  const core::Geometry g = core::build_on_rank_zero(
      [&] { return build_timed_geometry(c, false, &progress, &geometry_seconds); }, MPI_COMM_WORLD);
  ModelResult r = solve_meshless(c, g, c.output.vtu && root ? out->file("displacement").string() : std::string(),
                                 [&](const std::string& line) { progress.step(line); });
  if (!root) return 0;  // rank 0 writes the results files
  return finish_meshless_run(c, g, geometry_seconds, &r, out.get(), &progress);
}

/// `tissue cut`: the EFG model with the case's incision made progressively, as a scalpel does (/cut/steps
/// increments, one at the start of each of the first /cut/steps time steps; meshless::EfgModel::advance_cut).
int run_cut(const std::string& config, const std::string& out_dir) {
  const core::Case c = core::load_case(config);
  if (!c.cut)
    throw core::CaseError(config, "/cut", "required key is missing: `tissue cut` advances the case's incision");
  if (c.cut->steps > c.time.steps)
    throw core::CaseError(config, "/cut/steps",
                          fmt::format("expected at most {} increments (one per time step, /time/steps), got {}",
                                      c.time.steps, c.cut->steps));
  Progress progress("cut", 3 + c.time.steps + (c.cut->steps - 1));
  core::OutputDirectory out(out_dir);  // staged: nothing is left behind if anything below fails
  double geometry_seconds = 0.0;
  const core::Geometry g = build_timed_geometry(c, false, &progress, &geometry_seconds);
  ModelResult r = solve_meshless(c, g, c.output.vtu ? out.file("displacement").string() : std::string(),
                                 [&](const std::string& line) { progress.step(line); }, {}, /*progressive_cut=*/true);
  return finish_meshless_run(c, g, geometry_seconds, &r, &out, &progress);
}

/// `tissue solve NAME`: any registered model (experiments/models/model_registry.cpp) on one process.
int run_solve_model(const std::string& name, const std::string& config, const std::string& out_dir) {
  const std::unique_ptr<Model> m = make_model(name);
  const core::Case c = core::load_case(config);
  if (const std::string why = m->cannot_solve(c); !why.empty())
    throw std::runtime_error(fmt::format("solve {}: the model cannot solve {}: {}", name, config, why));
  Progress progress("solve " + name, 1 + m->progress_lines(c) + 1);
  core::OutputDirectory out(out_dir);  // staged: nothing is left behind if anything below fails
  progress.step("building the geometry (Gmsh)");
  core::GeometryOptions meshes;
  meshes.build_fem_mesh = m->needs_fem_mesh();
  meshes.build_node_cloud = m->needs_node_cloud();
  const double t0 = progress.elapsed_seconds();
  const core::Geometry g = core::build_geometry(c, meshes);
  const double geometry_seconds = progress.elapsed_seconds() - t0;
  SolveRequest request;
  if (c.output.vtu) request.vtu_prefix = out.file("displacement").string();
  request.on_step = [&](const std::string& line) { progress.step(line); };
  ModelResult r = m->solve(c, g, request);
  r.role = m->role();
  r.details["geometry_seconds"] = geometry_seconds;
  r.setup_seconds += geometry_seconds;
  r.total_seconds += geometry_seconds;
  describe_samples_near_cut(g, &r);
  write_model_files(out, c, r);
  out.commit();
  progress.done();
  print_summary(r);
  std::cout << fmt::format("wrote {}\n", out.destination().string());
  return 0;
}

}  // namespace

void add_solve_commands(CLI::App& app) {
  auto* group = app.add_subcommand("solve", "Solve a load case with one model and write its results folder");
  group->require_subcommand(1);

  auto* fem = group->add_subcommand("fem", "The deal.II FEM reference (also under `mpirun -np N`)");
  fem->footer("Writes a VTU per output step (pvtu + one piece per MPI process), samples.csv (eq. 33, mm), timings.json\n"
              "and case.json. Runs distributed under `mpirun -np N` (docs/FEM_REFERENCE.md).");
  static std::string fem_config, fem_out;
  fem->add_option("CONFIG", fem_config, "Load-case JSON file (schema: docs/CONFIG.md)")->required();
  fem->add_option("--out", fem_out, "Output folder (written atomically)")->required();
  fem->callback([] { throw CommandResult{run_solve_fem(fem_config, fem_out)}; });

  auto* efg = group->add_subcommand("meshless", "The EFG meshless model (also under `mpirun -np N`)");
  efg->footer("Writes a VTU per output step, samples.csv (eq. 33, mm), timings.json and case.json. Under `mpirun -np N`\n"
              "the PETSc Krylov solve is distributed over the N processes (for clouds too large to factorise;\n"
              "docs/MESHLESS.md §2).");
  static std::string efg_config, efg_out;
  efg->add_option("CONFIG", efg_config, "Load-case JSON file (schema: docs/CONFIG.md)")->required();
  efg->add_option("--out", efg_out, "Output folder (written atomically)")->required();
  efg->callback([] { throw CommandResult{run_solve_meshless(efg_config, efg_out)}; });

  // Every other registered model, by its name: adding a model to the registry adds its `tissue solve NAME`.
  // config and out per model; a deque, since CLI11 keeps pointers to the strings and a vector would move them
  static std::deque<std::pair<std::string, std::string>> model_args;
  for (const std::string& name : registered_model_names()) {
    if (name == "fem") continue;  // its own command above, which also runs under mpirun
    const std::unique_ptr<Model> m = make_model(name);
    auto* sub = group->add_subcommand(name, m->description());
    sub->footer("Writes samples.csv (eq. 33, mm), timings.json and case.json (and a VTU per output step where the\n"
                "model writes one). Role in comparisons: " + m->role() + ".");
    model_args.emplace_back();
    const std::size_t k = model_args.size() - 1;
    sub->add_option("CONFIG", model_args[k].first, "Load-case JSON file (schema: docs/CONFIG.md)")->required();
    sub->add_option("--out", model_args[k].second, "Output folder (written atomically)")->required();
    sub->callback([name, k] { throw CommandResult{run_solve_model(name, model_args[k].first, model_args[k].second)}; });
  }

  auto* cut = app.add_subcommand("cut", "Progressive incision with the EFG model");
  cut->footer("The case's cut advances along its polyline in /cut/steps increments (one at the start of each of the\n"
              "first /cut/steps time steps), each a local update of the shape functions and a re-solve with the history\n"
              "carried over. Writes per output step the node cloud's cells and the opened cut (VTU), then samples.csv,\n"
              "timings.json (with every update) and case.json.");
  static std::string cut_config, cut_out;
  cut->add_option("CONFIG", cut_config, "Load-case JSON file with a /cut (schema: docs/CONFIG.md)")->required();
  cut->add_option("--out", cut_out, "Output folder (written atomically)")->required();
  cut->callback([] { throw CommandResult{run_cut(cut_config, cut_out)}; });
}

}  // namespace experiments
