#include "experiments/commands/verify_commands.hpp"

#include "experiments/comparator/mesh_study_estimate.hpp"

#include <deal.II/base/mpi.h>
#include <fmt/format.h>

#include <cmath>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>

#include "core/case.hpp"
#include "core/convergence_rate.hpp"
#include "core/geometry.hpp"
#include "core/load_patch_zone.hpp"
#include "core/geometry_broadcast.hpp"
#include "core/output_directory.hpp"
#include "experiments/models/efg/meshless_runs.hpp"
#include "experiments/models/lrpim/lrpim_case_model.hpp"
#include "experiments/models/model_result.hpp"
#include "experiments/io/progress.hpp"
#include "experiments/io/rank_zero_output.hpp"
#include "reference_fem/fem_model.hpp"
#include "reference_fem/verification.hpp"

namespace experiments {
namespace {

struct VerifyFemOptions {
  std::string out = "results/verify";
  std::vector<std::string> configs{std::string(TISSUE_SOURCE_DIR) + "/configs/lung_small.json",
                                   std::string(TISSUE_SOURCE_DIR) + "/configs/lung_large.json"};
  /// One refinement ratio (1.5) between four levels, through the shipped cases' 12 mm to 8 mm: the comparator takes
  /// the reference's error bar at 12 mm from the 12 mm level's distance to the finest plus the finest level's
  /// Richardson estimate, and can take the extrapolated samples as its reference (docs/EXPERIMENTS.md).
  std::vector<double> sizes_mm{27.0, 18.0, 12.0, 8.0};
  std::vector<int> cantilever_levels{1, 2, 4, 8};
  double converged_change = 0.01;  ///< relative change of the sample displacements at the next level
  bool skip_lung = false;
  /// Meshes per level, at h (1 + jitter k), k = 0, +1, -1, +2, ...: Gmsh's levels are not nested, so each mesh's
  /// samples carry a part that depends on that mesh, which the observed order inherits; the level's samples are
  /// the meshes' mean, and the spread is reported (docs/FEM_REFERENCE.md, "Mesh-to-mesh noise").
  int meshes_per_level = 1;
  double jitter = 0.01;
};

/// The mesh sizes [mm] of the level of nominal size h: h (1 + jitter k), k = 0, +1, -1, +2, -2, ...
std::vector<double> level_mesh_sizes(double h, const VerifyFemOptions& opt) {
  std::vector<double> sizes;
  for (int m = 0; m < opt.meshes_per_level; ++m) {
    const int k = (m + 1) / 2 * (m % 2 == 1 ? 1 : -1);
    sizes.push_back(std::round(h * (1.0 + opt.jitter * k) * 1e6) / 1e6);  // to the nm, so that it prints as given
  }
  return sizes;
}

core::KelvinParameters bar_material(double nu) {
  core::KelvinParameters p;
  p.K1 = 2000.0;
  p.K2 = 1000.0;
  p.eta = 600.0;
  p.nu = nu;
  return p;
}

nlohmann::json verify_uniaxial(std::string* md) {
  using reference_fem::kCreepTolerance;
  using reference_fem::kRelaxationTolerance;
  using reference_fem::kSupportDisplacementTolerance;
  reference_fem::UniaxialOptions o;
  o.material = bar_material(0.3);
  o.end_time = 1.0;
  o.steps = 20;
  const auto relax = reference_fem::run_uniaxial_relaxation(o, 0.01);
  o.material = bar_material(0.0);
  o.end_time = 3.0;
  o.steps = 150;
  const auto creep = reference_fem::run_uniaxial_creep(o, 100.0);
  constexpr double kSupportStiffness = 1000.0;  // Pa/m: sigma0 / k_s = 0.1 m, beside the 2 m bar's own stretch
  const auto supported = reference_fem::run_uniaxial_creep_on_elastic_support(o, 100.0, kSupportStiffness);
  const bool pass = relax.max_relative_error < kRelaxationTolerance && creep.max_relative_error < kCreepTolerance &&
                    supported.max_relative_error < kCreepTolerance &&
                    supported.max_support_relative_error < kSupportDisplacementTolerance;
  auto row = [](const char* test, const char* steps, double error, double limit) {
    return fmt::format("| {} | {} | {:.2e} | {:.0e} | {} |\n", test, steps, error, limit, error < limit ? "yes" : "NO");
  };
  *md += "## Uniaxial bar (standard linear solid, closed forms)\n\n| test | steps | max relative error | limit | pass |\n"
         "|---|---|---|---|---|\n";
  *md += row("relaxation, eps0 = 1 %, nu = 0.3, dt = tau/4", "1 + 20", relax.max_relative_error, kRelaxationTolerance);
  *md += row("creep, sigma0 = 100 Pa, nu = 0, dt = tau/10", "1 + 150", creep.max_relative_error, kCreepTolerance);
  *md += row("creep on an elastic support (k_s = 1000 Pa/m): strain", "1 + 150", supported.max_relative_error,
             kCreepTolerance);
  *md += row("creep on an elastic support: the support's displacement sigma0 / k_s", "1 + 150",
             supported.max_support_relative_error, kSupportDisplacementTolerance);
  *md += "\n";
  return {{"relaxation",
           {{"max_relative_error", relax.max_relative_error}, {"steps", 21}, {"nu", 0.3}, {"limit", kRelaxationTolerance}}},
          {"creep", {{"max_relative_error", creep.max_relative_error}, {"steps", 151}, {"nu", 0.0}, {"limit", kCreepTolerance}}},
          {"creep_on_elastic_support",
           {{"max_relative_error", supported.max_relative_error},
            {"max_support_displacement_relative_error", supported.max_support_relative_error},
            {"support_stiffness_Pa_per_m", kSupportStiffness},
            {"limits", {kCreepTolerance, kSupportDisplacementTolerance}}}},
          {"pass", pass}};
}

nlohmann::json verify_cantilever(const VerifyFemOptions& opt, Progress* progress, std::string* md) {
  reference_fem::CantileverOptions o;
  std::vector<reference_fem::CantileverLevel> levels;
  nlohmann::json rows = nlohmann::json::array();
  *md += "## Cantilever vs Timoshenko beam (elastic limit, degree 2)\n\n| elements through depth | h [mm] | DOFs | "
         "relative L2 error | tip deflection / exact | rate | time [s] |\n|---|---|---|---|---|---|---|\n";
  for (int n : opt.cantilever_levels) {
    progress->step(fmt::format("cantilever, {} elements through the depth", n));
    levels.push_back(reference_fem::run_cantilever(o, n));
    const auto& l = levels.back();
    std::string rate = "";
    if (levels.size() > 1) {
      const auto& p = levels[levels.size() - 2];
      rate = fmt::format("{:.2f}", core::convergence_rate({p.h, l.h}, {p.l2_error, l.l2_error}));  // this pair's order
    }
    *md += fmt::format("| {} | {:.2f} | {} | {:.3e} | {:.6f} | {} | {:.1f} |\n", n, l.h * 1e3, l.n_dofs, l.l2_error,
                       l.tip_deflection / l.exact_tip_deflection, rate, l.seconds);
    rows.push_back({{"subdivisions", n},
                    {"h_mm", l.h * 1e3},
                    {"n_dofs", l.n_dofs},
                    {"relative_l2_error", l.l2_error},
                    {"tip_deflection_ratio", l.tip_deflection / l.exact_tip_deflection},
                    {"seconds", l.seconds}});
  }
  if (levels.size() < 2) {  // a study's lung levels with a single cantilever level (--cantilever-levels 1)
    *md += "\nOne level: no L2 rate (give --cantilever-levels two or more sizes).\n\n";
    return {{"levels", rows}, {"l2_rate", nullptr}, {"expected_rate", 3.0}, {"pass", nullptr}};
  }
  const double rate = reference_fem::convergence_rate(levels);
  *md += fmt::format("\nLeast-squares L2 rate: **{:.2f}** (expected 3 for degree 2; asserted >= 2.5)\n\n", rate);
  return {{"levels", rows}, {"l2_rate", rate}, {"expected_rate", 3.0}, {"pass", rate >= 2.5}};
}

/// The rows of an n x 3 matrix in metres as a JSON array of [x, y, z] in mm.
nlohmann::json rows_in_mm(const Eigen::MatrixXd& m) {
  nlohmann::json rows = nlohmann::json::array();
  for (Eigen::Index i = 0; i < m.rows(); ++i) rows.push_back({m(i, 0) * 1e3, m(i, 1) * 1e3, m(i, 2) * 1e3});
  return rows;
}

/// One mesh level of one case.
struct LungLevel {
  double h_mm = 0.0;
  reference_fem::FemRunResult run;  ///< on the mesh of size h itself
  std::string error;  ///< non-empty when a solve failed (e.g. Newton did not converge)
  /// Each mesh's size [mm] and samples [m] (the first is h's); `samples` is their mean, what the study uses.
  std::vector<double> mesh_sizes_mm;
  std::vector<Eigen::MatrixXd> mesh_samples;
  Eigen::MatrixXd samples;
  double seconds = 0.0;  ///< over the level's meshes
  /// Where the samples lie, for their grouping by the refined ball (the same at every level: they are chosen on
  /// the reference surface) [m].
  core::PointMatrix sample_points;
  Eigen::Vector3d load_centre = Eigen::Vector3d::Zero();
};

/// Solve every case at every mesh size, one after the other: Gmsh is a process-wide singleton, and the FEM's
/// Trilinos objects make MPI calls, which MPI (initialised for one thread at a time) does not allow from
/// concurrent threads. Each solve assembles with all the cores. Under mpirun, rank 0 meshes each level and every
/// process solves it with the others (reference_fem/fem_model.hpp), so a level may need more memory than one process
/// has; every process returns the same levels. Collective over MPI_COMM_WORLD.
std::vector<std::vector<LungLevel>> solve_lung_levels(const VerifyFemOptions& opt, const std::vector<core::Case>& cases,
                                                       Progress* progress) {
  const bool root = dealii::Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0;
  std::vector<std::vector<LungLevel>> levels(cases.size());
  for (double h : opt.sizes_mm) {
    for (auto& case_levels : levels) case_levels.push_back(LungLevel{h});
    for (const double size : level_mesh_sizes(h, opt)) {
      std::vector<core::Geometry> geometries;
      for (const auto& c : cases) {
        progress->step(fmt::format("{}: mesh size {} mm", c.name, size));
        core::GeometryOptions g_options;
        g_options.fem_mesh_size = size * 1e-3;
        g_options.build_node_cloud = false;
        geometries.push_back(core::build_on_rank_zero([&] { return core::build_geometry(c, g_options); },
                                                      MPI_COMM_WORLD));
      }
      for (std::size_t i = 0; i < cases.size(); ++i) {
        LungLevel& level = levels[i].back();
        if (level.mesh_sizes_mm.empty()) {
          level.sample_points = geometries[i].sample_points;
          level.load_centre = geometries[i].load_centre;
        }
        if (!level.error.empty()) continue;  // a mesh of this level failed: the level has no mean
        try {
          reference_fem::FemRunResult r = reference_fem::run_case(cases[i], geometries[i]);  // on MPI_COMM_WORLD
          if (root)
            std::cerr << fmt::format("  {} at {} mm: {} DOFs, max sample |u| {:.4f} mm, {:.1f} s\n", cases[i].name, size,
                                   r.n_dofs, r.sample_displacements.rowwise().norm().maxCoeff() * 1e3, r.total_seconds);
          level.mesh_sizes_mm.push_back(size);
          level.mesh_samples.push_back(r.sample_displacements);
          level.seconds += r.total_seconds;
          if (level.mesh_sizes_mm.size() == 1) level.run = std::move(r);
        } catch (const std::exception& e) {  // recorded in fem.json; the other cases and levels go on
          level.error = opt.meshes_per_level > 1 ? fmt::format("at {} mm: {}", size, e.what()) : e.what();
          if (root) std::cerr << fmt::format("  {} at {} mm FAILED: {}\n", cases[i].name, size, e.what());
        }
      }
    }
    for (auto& case_levels : levels) {
      LungLevel& level = case_levels.back();
      if (!level.error.empty()) continue;
      level.samples = Eigen::MatrixXd::Zero(level.mesh_samples.front().rows(), 3);
      for (const auto& u : level.mesh_samples) level.samples += u / static_cast<double>(level.mesh_samples.size());
    }
  }
  return levels;
}

/// The observed orders of the samples within core::kLoadPatchBallRadii load radii of the load centre and of those
/// beyond, apart (experiments::observed_orders): with the load patch graded over its ball the two groups are refined
/// at different rates. Null when either group is empty. The JSON has a "sentence" for fem.md.
nlohmann::json orders_by_zone(const core::Case& c, const LungLevel& level, const std::vector<Eigen::MatrixXd>& u,
                              const std::vector<double>& h_mm) {
  const double ball = core::kLoadPatchBallRadii * c.load.radius;
  std::vector<Eigen::Index> within, beyond;
  for (Eigen::Index i = 0; i < level.sample_points.rows(); ++i)
    (level.sample_points.row(i).transpose() - level.load_centre).norm() <= ball ? within.push_back(i)
                                                                              : beyond.push_back(i);
  if (within.empty() || beyond.empty()) return nullptr;
  // The grading zone "edge" grades only a band along the patch's edge, so the ball itself falls like h.
  const std::string within_rate =
      c.geometry.load_patch_grading_zone == core::GeometrySpec::LoadPatchGradingZone::edge
          ? fmt::format("h (graded like h^{:g} only along the patch's edge)", c.geometry.load_patch_grading)
          : fmt::format("h^{:g}", c.geometry.load_patch_grading);
  const std::vector<double> orders_within = observed_orders(u, h_mm, within);
  const std::vector<double> orders_beyond = observed_orders(u, h_mm, beyond);
  auto listed = [](const std::vector<double>& orders) {
    std::vector<std::string> s;
    for (double p : orders) s.push_back(p > 0 ? fmt::format("{:.2f}", p) : "none (not decreasing)");
    return fmt::format("{}", fmt::join(s, ", "));
  };
  return {{"ball_radius_mm", ball * 1e3},
          {"within", {{"samples", within}, {"observed_orders", orders_within}}},
          {"beyond", {{"samples", beyond}, {"observed_orders", orders_beyond}}},
          {"sentence",
           fmt::format("By zone (the refined ball of {:.1f} mm about the load centre, where the local size falls like "
                       "{}; beyond it like h): observed orders {} for the {} samples within, {} for the {} "
                       "beyond.",
                       ball * 1e3, within_rate, listed(orders_within), within.size(), listed(orders_beyond),
                       beyond.size())}};
}

nlohmann::json summarize_lung(const VerifyFemOptions& opt, const std::string& config, const core::Case& c,
                              const std::vector<LungLevel>& levels, std::string* md) {
  std::vector<Eigen::MatrixXd> u;
  std::vector<std::string> noise_lines;
  nlohmann::json rows = nlohmann::json::array();
  *md += fmt::format("## Mesh convergence: {} (degree {})\n\n| mesh size [mm] | tets | DOFs | Newton its | crack faces | "
                     "max sample |u| [mm] | change to previous level | probe strain mean / peak | support-edge strain mean / peak "
                     "| time [s] |\n"
                     "|---|---|---|---|---|---|---|---|---|---|\n",
                     c.name, c.fem.degree);
  for (const auto& level : levels) {
    const double h = level.h_mm;
    if (!level.error.empty()) {
      *md += fmt::format("| {} | failed: {} | | | | | | | | |\n", h, level.error);
      rows.push_back({{"mesh_size_mm", h}, {"error", level.error}});
      continue;
    }
    const reference_fem::FemRunResult& r = level.run;
    u.push_back(level.samples);
    int its = 0;
    for (const auto& s : r.steps) its += s.newton_iterations;
    std::optional<double> change;
    if (u.size() > 1) change = (u[u.size() - 1] - u[u.size() - 2]).norm() / u.back().norm();
    *md += fmt::format("| {} | {} | {} | {} | {} | {:.4f} | {} | {:.1f} % / {:.1f} % | {:.2f} % / {:.2f} % | {:.1f} |\n",
                       h, r.n_cells, r.n_dofs, its, r.crack_faces, level.samples.rowwise().norm().maxCoeff() * 1e3,
                       change ? fmt::format("{:.2f} %", *change * 100) : "", r.probe_strain.mean * 100,
                       r.probe_strain.peak * 100, r.support_edge_strain.mean * 100, r.support_edge_strain.peak * 100,
                       level.seconds);
    rows.push_back({{"mesh_size_mm", h},
                    {"n_cells", r.n_cells},
                    {"n_dofs", r.n_dofs},
                    {"newton_iterations", its},
                    {"crack_faces", r.crack_faces},
                    {"probe_strain_mean", r.probe_strain.mean},
                    {"probe_strain_peak", r.probe_strain.peak},
                    {"support_edge_strain_mean", r.support_edge_strain.mean},
                    {"support_edge_strain_peak", r.support_edge_strain.peak},
                    {"support_edge_band_mm", reference_fem::kSupportEdgeBand * 1e3},
                    {"seconds", level.seconds},
                    {"mpi_processes", r.mpi_processes},
                    // The smallest 1 + 2k lambda of the converged states, and where: below the law's slope floor the
                    // law was continued there (docs/MATERIAL.md §1.7).
                    {"min_one_plus_2k_lambda", r.smallest_margin.margin},
                    {"min_one_plus_2k_lambda_at_mm", std::vector<double>{r.smallest_margin.point.x() * 1e3,
                                                                         r.smallest_margin.point.y() * 1e3,
                                                                         r.smallest_margin.point.z() * 1e3}},
                    {"sample_displacements_mm", rows_in_mm(level.samples)},
                    {"relative_change_to_previous", change ? nlohmann::json(*change) : nlohmann::json()}});
    if (level.mesh_samples.size() > 1) {
      // The spread of the meshes about their mean: RMS over the samples of each mesh's distance, with n - 1.
      double sum = 0.0;
      nlohmann::json meshes = nlohmann::json::array();
      for (std::size_t m = 0; m < level.mesh_samples.size(); ++m) {
        sum += (level.mesh_samples[m] - level.samples).rowwise().squaredNorm().mean();
        meshes.push_back({{"mesh_size_mm", level.mesh_sizes_mm[m]},
                          {"sample_displacements_mm", rows_in_mm(level.mesh_samples[m])}});
      }
      const double noise = std::sqrt(sum / static_cast<double>(level.mesh_samples.size() - 1));
      rows.back()["meshes"] = meshes;
      rows.back()["mesh_noise_mm"] = noise * 1e3;
      noise_lines.push_back(fmt::format("{} mm: {:.2f} µm ({:.3f} % of the largest sample)", h, noise * 1e6,
                                        100 * noise / level.samples.rowwise().norm().maxCoeff()));
    }
  }
  if (c.material.k != 0.0) {
    std::vector<std::string> margins;
    for (const auto& level : levels)
      if (level.error.empty())
        margins.push_back(fmt::format("{} mm: {:.3f} at ({:.1f}, {:.1f}, {:.1f}) mm", level.h_mm,
                                      level.run.smallest_margin.margin, level.run.smallest_margin.point.x() * 1e3,
                                      level.run.smallest_margin.point.y() * 1e3,
                                      level.run.smallest_margin.point.z() * 1e3));
    const double floor = c.material.slope_floor;
    *md += fmt::format("\nSmallest 1 + 2k lambda of the converged states (the law's margin, docs/MATERIAL.md §1.5): {}. "
                       "{}\n",
                       fmt::join(margins, "; "),
                       floor > 0.0 ? fmt::format("The law's slope floor is {:g}: below it, the law was continued past "
                                                 "the paper's range there (§1.7).", floor)
                                   : "No slope floor: the paper's law throughout.");
  }
  if (!noise_lines.empty())
    *md += fmt::format("\nEach level is the mean of {} meshes at h (1 + {:g} k), k = 0, +1, -1, ...; the table's mesh, "
                       "DOFs and strains are those of h itself, its time the meshes' total. Mesh-to-mesh noise (RMS "
                       "over the samples of each mesh's distance from the mean): {}.\n",
                       opt.meshes_per_level, opt.jitter, fmt::join(noise_lines, "; "));
  // Converged: the first level whose samples change by less than the threshold at the next level.
  nlohmann::json converged;
  bool all_solved = true;
  for (const auto& level : levels) all_solved = all_solved && level.error.empty();
  for (std::size_t l = 0; all_solved && l + 1 < u.size(); ++l)
    if ((u[l + 1] - u[l]).norm() / u[l + 1].norm() < opt.converged_change) {
      converged = levels[l].h_mm;
      break;
    }
  // Richardson on the last three levels (norms of the differences of all sample displacements).
  nlohmann::json richardson;
  if (all_solved && u.size() >= 3) {
    std::vector<double> h_mm;
    for (const auto& level : levels) h_mm.push_back(level.h_mm);
    const MeshStudyEstimate estimate = estimate_remaining_error(u, h_mm, expected_sample_order(c));
    richardson = estimate.json;
    if (estimate.extrapolated.size() > 0)  // the comparator's `--reference extrapolated`
      richardson["extrapolated_sample_displacements_mm"] = rows_in_mm(estimate.extrapolated);
    *md += "\n" + estimate.sentence + "\n";
    if (const std::string hint = one_mesh_per_level_hint(estimate, opt.meshes_per_level); !hint.empty())
      *md += hint + "\n";
    if (nlohmann::json zones = orders_by_zone(c, levels.back(), u, h_mm); !zones.is_null()) {
      *md += zones["sentence"].get<std::string>() + "\n";
      zones.erase("sentence");
      richardson["observed_orders_by_zone"] = zones;
    }
  }
  *md += converged.is_null()
             ? fmt::format("Not converged to {:.0f} % within these levels.\n\n", opt.converged_change * 100)
             : fmt::format("Converged (< {:.0f} % change at the next level) at mesh size **{} mm**.\n\n",
                           opt.converged_change * 100, converged.get<double>());
  const nlohmann::json sample_points = levels.empty() ? nlohmann::json::array() : rows_in_mm(levels.front().sample_points);
  const Eigen::Vector3d centre_mm = levels.empty() ? Eigen::Vector3d::Zero() : Eigen::Vector3d(levels.front().load_centre * 1e3);
  return {{"config", config},
          {"case", c.name},
          {"degree", c.fem.degree},
          {"sample_points_mm", sample_points},
          {"load_centre_mm", {centre_mm.x(), centre_mm.y(), centre_mm.z()}},
          {"load_radius_mm", c.load.radius * 1e3},
          {"levels", rows},
          {"richardson", richardson},
          {"converged_mesh_size_mm", converged},
          {"criterion", fmt::format("||u_next - u||/||u_next|| over all sample displacements < {}", opt.converged_change)}};
}

int run_verify_fem(const VerifyFemOptions& opt) {
  // Under mpirun every process runs this function: each solves the small closed-form problems alone (they take
  // seconds), all of them solve the lung levels together, and rank 0 meshes, prints and writes.
  const bool root = dealii::Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0;
  const unsigned int n_processes = dealii::Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD);
  const int lung_steps =
      opt.skip_lung ? 0 : static_cast<int>(opt.configs.size() * opt.sizes_mm.size()) * opt.meshes_per_level;
  Progress progress("verify fem", 1 + static_cast<int>(opt.cantilever_levels.size()) + lung_steps, !root);
  const std::unique_ptr<core::OutputDirectory> out = stage_on_rank_zero(opt.out);
  std::string md = "# FEM reference verification (`tissue verify fem`)\n\n";
  nlohmann::json j;
  progress.step("uniaxial relaxation and creep");
  j["uniaxial"] = verify_uniaxial(&md);
  j["cantilever"] = verify_cantilever(opt, &progress, &md);
  if (!opt.skip_lung) {
    std::vector<core::Case> cases;
    for (const auto& config : opt.configs) cases.push_back(core::load_case(config));
    const auto levels = solve_lung_levels(opt, cases, &progress);
    if (!root) return 0;  // rank 0 summarises and writes
    if (n_processes > 1)
      md += fmt::format("The lung levels were solved on {} MPI processes (mpirun), each mesh built by rank 0.\n\n",
                        n_processes);
    nlohmann::json lung = nlohmann::json::object();
    for (std::size_t i = 0; i < cases.size(); ++i)
      lung[cases[i].name] = summarize_lung(opt, opt.configs[i], cases[i], levels[i], &md);
    j["mesh_convergence"] = lung;
    // The comparator uses one FEM mesh size for all cases: the coarsest that converged everywhere.
    nlohmann::json size;
    for (const auto& [name, r] : lung.items()) {
      if (r["converged_mesh_size_mm"].is_null()) {
        size = nullptr;
        break;
      }
      const double s = r["converged_mesh_size_mm"].get<double>();
      size = size.is_null() ? s : std::min(size.get<double>(), s);
    }
    j["reference_mesh_size_mm"] = size;
  }
  if (!root) return 0;  // --skip-lung: rank 0 writes
  write_text_file(out->file("fem.json").string(), j.dump(2) + "\n");
  write_text_file(out->file("fem.md").string(), md);
  out->commit();
  progress.done();
  std::cout << md;
  return 0;
}

}  // namespace

void add_verify_commands(CLI::App& app) {
  auto* group = app.add_subcommand("verify", "Verify a model against closed forms and its own mesh convergence");
  group->require_subcommand(1);
  auto* fem = group->add_subcommand("fem", "The FEM reference: closed forms, cantilever rate, lung mesh convergence");
  fem->footer("Uniaxial relaxation and creep against their closed forms, the Timoshenko cantilever's L2 rate and the lung\n"
              "mesh convergence study (the reference's error bar for compare); writes fem.json and fem.md. Under\n"
              "`mpirun -np N` every lung level is solved by the N processes together (docs/FEM_REFERENCE.md).");
  static VerifyFemOptions opt;
  fem->add_option("--out", opt.out, "Output folder (written atomically)")->capture_default_str();
  fem->add_option("--config", opt.configs, "Load cases for the mesh-convergence study")->capture_default_str();
  fem->add_option("--sizes", opt.sizes_mm, "FEM mesh sizes [mm], coarse to fine")->capture_default_str();
  fem->add_option("--cantilever-levels", opt.cantilever_levels, "Elements through the cantilever depth")
      ->capture_default_str();
  fem->add_flag("--skip-lung", opt.skip_lung, "Only the closed-form checks (fast)");
  fem->add_option("--meshes-per-level", opt.meshes_per_level,
                  "Meshes per level, at h (1 + jitter k), k = 0, +1, -1, ...; the level's samples are their mean and "
                  "their spread is reported (the levels are not nested: docs/FEM_REFERENCE.md, \"Mesh-to-mesh noise\")")
      ->check(CLI::Range(1, 9))
      ->capture_default_str();
  fem->add_option("--jitter", opt.jitter, "Relative size step between a level's meshes")
      ->check(CLI::Range(0.001, 0.05))
      ->capture_default_str();
  fem->callback([] { throw CommandResult{run_verify_fem(opt)}; });

  auto* efg = group->add_subcommand("meshless",
                                    "The EFG model: MLS invariants, patch test, cantilever rates, creep, crack opening");
  efg->footer("The MLS invariants, the patch test against the quadrature order, the Timoshenko cantilever's L2 and energy\n"
              "rates, the creep bar and the crack's opening against the FEM crack (docs/MESHLESS.md §3, §5.2); writes\n"
              "meshless.json and meshless.md.");
  static std::string efg_out = "results/verify";
  static bool efg_quick = false;
  efg->add_option("--out", efg_out, "Output folder (written atomically)")->capture_default_str();
  efg->add_flag("--quick", efg_quick,
                "Fewer quadrature orders and cantilever levels, no crack opening (10 s instead of 3.5 min)");
  efg->callback([] { throw CommandResult{run_verify_meshless(efg_out, efg_quick)}; });

  auto* lrpim = group->add_subcommand("lrpim", "The LRPIM model: RPIM invariants, patch tests, cantilever rates, creep");
  lrpim->footer("The RPIM shape functions' invariants, the linear patch test (box and triangulated body), the Timoshenko\n"
                "cantilever's L2 and energy rates and the creep bar at k = 0 and k = 2 against their closed forms;\n"
                "writes lrpim.json and lrpim.md (docs/LRPIM.md §4). Exit 1 when a figure misses its bound.");
  static std::string lrpim_out = "results/verify";
  static bool lrpim_quick = false;
  lrpim->add_option("--out", lrpim_out, "Output folder (written atomically)")->capture_default_str();
  lrpim->add_flag("--quick", lrpim_quick, "Smaller clouds and fewer steps (looser bounds where the set is smaller)");
  lrpim->callback([] { throw CommandResult{run_verify_lrpim(lrpim_out, lrpim_quick)}; });
}

}  // namespace experiments
