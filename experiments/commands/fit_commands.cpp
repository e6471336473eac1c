#include "experiments/commands/fit_commands.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>

#include "core/case.hpp"
#include "core/geometry.hpp"
#include "experiments/io/progress.hpp"
#include "meshless/efg/efg_problem.hpp"
#include "meshless/surrogate/surrogate_builder.hpp"
#include "meshless/surrogate/surrogate_file.hpp"

namespace experiments {
namespace {

struct FitArguments {
  std::string config, out;
  double memory_budget_gb = 4.0;
  int workers = 0;
  bool check_patch = false;
};

core::Geometry node_cloud(const core::Case& c) {
  core::GeometryOptions options;
  options.build_fem_mesh = false;
  options.build_node_cloud = true;
  return core::build_geometry(c, options);
}

void print_fit(const meshless::SurrogateData& d, const meshless::SurrogateBuildReport& r) {
  std::cout << fmt::format(
      "surrogate of '{}': {} contact node(s), {} surface nodes, displacements at t = {:g} s ({}), forces per "
      "axis in "
      "[-{:g}, {:g}] N at {} levels\n",
      d.case_name, d.contacts.size(), d.surface_position.rows(), d.response_seconds, d.response_time,
      d.max_force, d.max_force, d.levels.size());
  std::cout << fmt::format(
      "training: {} full solves on {} worker(s) ({:.2f} GB per model) in {:.1f} s; fits in {:.1f} s\n",
      r.training_solves, r.training.workers, r.training.model_bytes / 1e9, r.training.wall_seconds,
      r.fit_seconds);
  std::map<std::string, int> terminations;
  int fits = 0, dropped_columns = 0, columns = 0;
  for (std::size_t c = 0; c < d.contacts.size(); ++c) {
    const meshless::ContactFit& f = d.contacts[c];
    const Eigen::Vector3d x = f.frame.origin * 1e3;
    const std::string snapped =
        d.region ? (c == 0 ? fmt::format("the region's centre node, {:.2f} mm from its configured centre",
                                         r.snap_distance[0] * 1e3)
                           : std::string("a region node"))
                 : fmt::format("snapped {:.2f} mm", r.snap_distance[c] * 1e3);
    std::cout << fmt::format("contact {} at ({:.2f}, {:.2f}, {:.2f}) mm ({}):\n", c + 1, x.x(), x.y(), x.z(),
                             snapped);
    std::cout << "  axis  lambda (CV eqs. 25-27 [mm])  field lambda (CV [mm])  (a,b,c) CV eq. 28 [mm] for "
                 "u_x | u_y | u_z"
                 "  training RMS eq. 28 [mm]\n";
    for (int j = 0; j < 3; ++j) {
      const meshless::AxisFit& a = f.axis[j];
      std::string fields;
      for (int i = 0; i < 3; ++i)
        fields += fmt::format("{}({},{},{}) {:.2e}", i ? " | " : "", a.field[i].tangential_order,
                              a.field[i].normal_order, a.field[i].contact_order, a.field[i].cv_rms * 1e3);
      std::cout << fmt::format("  {}     {} ({:.2e})                 {} ({:.2e})          {}  {:.2e}\n",
                               "xyz"[j], a.force_order, a.contact_cv_rms * 1e3, a.field_order,
                               a.field_order_cv_rms * 1e3, fields, a.training_rms * 1e3);
    }
    for (const meshless::FitSummary& s : f.summaries) {
      ++terminations[s.termination];
      ++fits;
      if (s.termination != "SOLVED") continue;
      columns += s.num_parameters;
      dropped_columns += s.num_parameters - s.rank;
    }
  }
  std::string counts;
  for (const auto& [name, n] : terminations)
    counts += fmt::format("{}{} {}", counts.empty() ? "" : ", ", n, name);
  std::cout << fmt::format(
      "linear least squares (scaled columns, pivoted QR): {} fits ({}); {} of their {} basis columns dropped "
      "as dependent\n",
      fits, counts, dropped_columns, columns);
  double worst_untrained = -1.0;
  for (const meshless::HoldoutError& e : r.holdouts) {
    const Eigen::Vector3d x = d.surface_position.row(e.load.contact).transpose() * 1e3;
    std::cout << fmt::format(
        "held-out force ({:.4g}, {:.4g}, {:.4g}) N at {} node ({:.2f}, {:.2f}, {:.2f}) mm: RMSE over the surface "
        "{:.4g} mm = {:.2f} % of the contact-node displacement ({:.4g} mm), {:.2f} % of the trained peak; "
        "contact-node error {:.4g} mm\n",
        e.load.force.x(), e.load.force.y(), e.load.force.z(), e.trained_contact ? "trained" : "UNTRAINED region",
        x.x(), x.y(), x.z(), e.rmse * 1e3, 100 * e.relative, e.contact_displacement * 1e3,
        100 * e.rmse / r.peak_contact_displacement, e.contact_error * 1e3);
    if (!std::isnan(e.rmse_near_cut))
      std::cout << fmt::format(
          "  on the cut body: RMSE {:.4g} mm = {:.2f} % near the lips (surface nodes within {:.3g} mm of the cut), "
          "{:.4g} mm = {:.2f} % away from them\n",
          e.rmse_near_cut * 1e3, 100 * e.rmse_near_cut / e.contact_displacement, r.near_cut_distance * 1e3,
          e.rmse_away_from_cut * 1e3, 100 * e.rmse_away_from_cut / e.contact_displacement);
    if (!e.trained_contact) worst_untrained = std::max(worst_untrained, e.relative);
  }
  if (worst_untrained >= 0.0)
    std::cout << fmt::format(
        "contact region: largest held-out RMSE at an untrained node {:.2f} % of its contact-node displacement, "
        "for {} training solves\n",
        100 * worst_untrained, r.training_solves);
}

int run_fit(const FitArguments& a) {
  const core::Case c = core::load_case(a.config);
  const core::SurrogateSpec& spec = c.surrogate;
  if (c.cut)
    std::cerr << "note: " << a.config
              << ": the surrogate is trained on the body cut by the whole of /cut (the incision is not advanced "
                 "in steps)\n";
  const int contacts = spec.contact_region ? spec.contact_region->training_contacts
                                           : static_cast<int>(spec.contact_points.size());
  const int holdouts =
      spec.holdout_forces * (1 + (spec.contact_region ? spec.contact_region->holdout_contacts : 0));
  const int solves = 3 * contacts * 2 * spec.force_levels;
  Progress progress("fit", 3 + solves + contacts + holdouts + (spec.contact_region ? 2 : 0));
  progress.step("building geometry and the node cloud (Gmsh)");
  const core::Geometry g = node_cloud(c);
  meshless::SurrogateBuildOptions options;
  options.memory_budget_bytes = a.memory_budget_gb * 1e9;
  options.max_workers = a.workers;
  meshless::SurrogateBuildReport report;
  meshless::SurrogateData d = meshless::build_surrogate(
      meshless::problem_from_case(c, g), spec, options, [&](const std::string& line) { progress.step(line); },
      &report);
  d.case_name = c.name;
  d.case_hash = meshless::surrogate_case_hash(c);
  progress.step("writing " + a.out);
  const std::filesystem::path out(a.out);
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  meshless::write_surrogate(a.out, d);
  progress.done();
  print_fit(d, report);
  std::cout << fmt::format("wrote {} ({:.1f} kB)\n", a.out, std::filesystem::file_size(out) / 1e3);
  return 0;
}

/// The training patch on the case's own cloud against the case's imprinted load patch: same force, same
/// cloud.
int run_check_patch(const FitArguments& a) {
  const core::Case c = core::load_case(a.config);
  Progress progress("fit --check-patch", 3);
  progress.step("building geometry and the node cloud (Gmsh)");
  const core::Geometry g = node_cloud(c);
  const meshless::EfgProblem problem = meshless::problem_from_case(c, g);
  const meshless::SurfaceNodes surface = meshless::surface_nodes(problem.mesh);
  double snap = 0.0;
  meshless::PatchLoad load;
  load.contact = surface.nearest(g.load_centre, &snap);
  load.force = c.load.force;
  meshless::PatchSolveOptions options;
  options.patch_radius = c.surrogate.patch_radius;
  options.response_step =
      meshless::response_step(problem, c.surrogate.response_time == core::SurrogateSpec::ResponseTime::end);
  progress.step(fmt::format("solving the imprinted patch and the training patch ({} steps each)",
                            options.response_step));
  const meshless::PatchComparison p = meshless::compare_load_patches(problem, {}, surface, load, options);
  progress.done();
  const Eigen::Vector3d ui = p.imprinted.row(load.contact).transpose(),
                        up = p.patch.row(load.contact).transpose();
  const double rmse = std::sqrt((p.imprinted - p.patch).rowwise().squaredNorm().mean());
  std::cout << fmt::format(
      "case '{}', force ({:g}, {:g}, {:g}) N, load centre snapped to surface node {:.2f} mm away, t = {:g} "
      "s\n"
      "imprinted load patch (faces tagged load): {} faces, {:.2f} mm^2\n"
      "training patch (face centroids within {:g} mm of the node): {} faces, {:.2f} mm^2\n"
      "contact-node displacement: imprinted ({:.4f}, {:.4f}, {:.4f}) mm |u| {:.4f} mm; training ({:.4f}, "
      "{:.4f}, "
      "{:.4f}) mm |u| {:.4f} mm ({:+.2f} %)\n"
      "RMSE over {} surface nodes: {:.4g} mm = {:.2f} % of the imprinted contact-node displacement; largest "
      "difference {:.4g} mm\n",
      c.name, c.load.force.x(), c.load.force.y(), c.load.force.z(), snap * 1e3,
      problem.step_times[options.response_step - 1], p.imprinted_faces, p.imprinted_area * 1e6,
      options.patch_radius * 1e3, p.patch_faces, p.patch_area * 1e6, ui.x() * 1e3, ui.y() * 1e3, ui.z() * 1e3,
      ui.norm() * 1e3, up.x() * 1e3, up.y() * 1e3, up.z() * 1e3, up.norm() * 1e3,
      100 * (up.norm() / ui.norm() - 1), surface.size(), rmse * 1e3, 100 * rmse / ui.norm(),
      (p.imprinted - p.patch).rowwise().norm().maxCoeff() * 1e3);
  return 0;
}

}  // namespace

void add_fit_commands(CLI::App& app) {
  auto* fit = app.add_subcommand("fit", "Train the force -> displacement surrogate (paper §3) and write it to FILE");
  fit->footer("Trains the surrogate (eqs. 25-28) on the case's node cloud with the full meshless model, fits it by linear\n"
              "least squares (orders by cross-validation), checks it on held-out forces and writes FILE. Options come\n"
              "from the case's /surrogate block (docs/SURROGATE.md).");
  static FitArguments args;
  fit->add_option("CONFIG", args.config, "Load-case JSON file (schema: docs/CONFIG.md, /surrogate)")
      ->required();
  auto* out = fit->add_option("--out", args.out, "Surrogate file to write (atomically)");
  fit->add_option("--memory-budget", args.memory_budget_gb,
                  "GB the concurrent full models may hold together (each worker keeps one model; default 4)")
      ->check(CLI::PositiveNumber);
  fit->add_option("--workers", args.workers,
                  "Concurrent full solves at most (default: the cores, within the budget)")
      ->check(CLI::NonNegativeNumber);
  fit->add_flag(
      "--check-patch", args.check_patch,
      "Instead of fitting: solve the case's force on its imprinted load patch and on the training patch "
      "around the nearest surface node (same cloud), and print the difference");
  fit->callback([out] {
    if (args.check_patch) throw CommandResult{run_check_patch(args)};
    if (out->count() == 0) throw CLI::RequiredError("--out");
    throw CommandResult{run_fit(args)};
  });
}

}  // namespace experiments
