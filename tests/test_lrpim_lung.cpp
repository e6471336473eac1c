// The LRPIM model on the built-in lung (configs/lung_small.json: 10 mm node cloud, elastic support, k = 1) against
// the FEM reference on the same geometry: eq. 34's RMSE over the case's samples relative to the largest FEM sample
// displacement (docs/LRPIM.md §5), with the time split and the memory. And a real STL lobe
// (../shared/data/lung, configs/lung_stl.json, a clamp) when that folder exists. Label `long`. All disabled while
// the lung's linear solve fails (docs/LRPIM.md §5); --gtest_also_run_disabled_tests runs them.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <iostream>

#include "core/case.hpp"
#include "core/geometry.hpp"
#include "meshless/lrpim/lrpim_case.hpp"
#include "reference_fem/fem_model.hpp"

namespace meshless::lrpim {
namespace {

// The lung runs' linear solver: PETSc with LrpimCaseOptions' Krylov options, or those of the environment variable
// LRPIM_KRYLOV_OPTIONS (for measuring others without a rebuild); LRPIM_SOLVER=mumps selects MUMPS instead, and
// LRPIM_NO_DIVERGENCE_CORRECTION (set) turns the correction off (docs/LRPIM.md §5).
LrpimCaseOptions lung_options() {
  LrpimCaseOptions options;
  options.linear_solver = LrpimLinearSolver::petsc_krylov;
  if (const char* k = std::getenv("LRPIM_KRYLOV_OPTIONS")) options.krylov_options = k;
  if (const char* s = std::getenv("LRPIM_SOLVER"); s && std::string(s) == "mumps")
    options.linear_solver = LrpimLinearSolver::mumps;
  if (std::getenv("LRPIM_NO_DIVERGENCE_CORRECTION")) options.divergence_correction = false;
  options.on_step = [](const LrpimStepReport& s) {
    std::cout << "LRPIM step " << s.step << " t = " << s.time << " s: " << s.newton_iterations << " iterations, "
              << s.factorisations << " factorisations, residual " << s.residuals.back() << ", " << s.wall_seconds
              << " s" << std::endl;
  };
  return options;
}

struct Score {
  double rmse = 0.0, peak = 0.0;  // [m]
};

// Eq. 34: sqrt(mean_i |u_model - u_fem|^2), and the largest |u_fem| of the samples.
Score score(const Eigen::MatrixXd& model, const Eigen::MatrixXd& fem) {
  Score s;
  for (Eigen::Index i = 0; i < fem.rows(); ++i) {
    s.rmse += (model.row(i) - fem.row(i)).squaredNorm();
    s.peak = std::max(s.peak, fem.row(i).norm());
  }
  s.rmse = std::sqrt(s.rmse / fem.rows());
  return s;
}

void print_run(const std::string& label, const LrpimCaseRun& run, const Score& s) {
  double assembly = 0.0, solve = 0.0;
  int iterations = 0;
  for (const LrpimStepReport& st : run.steps) assembly += st.assembly_seconds, solve += st.solve_seconds,
                                              iterations += st.newton_iterations;
  std::cout << label << ": " << run.n_nodes << " nodes, " << run.n_dofs << " DOFs; RMSE " << s.rmse * 1e3
            << " mm = " << 100.0 * s.rmse / s.peak << " % of the peak FEM sample " << s.peak * 1e3 << " mm; set-up "
            << run.setup_seconds << " s, assembly " << assembly << " s, solve " << solve << " s, " << iterations
            << " Newton iterations, " << run.details["factorisations"] << " factorisations, peak RSS "
            << run.details["peak_resident_bytes"].get<double>() / 1e9 << " GB\n"
            << "  " << run.details.dump() << "\n";
}

// Disabled until the lung's linear solve works (docs/LRPIM.md §5: every solver tried fails on the lung's tangent);
// run it with --gtest_also_run_disabled_tests. The 5 % bound is a placeholder to be set from the first measurement.
TEST(LrpimLung, DISABLED_LungSmallAgainstTheFemReference) {
  const core::Case c = core::load_case(std::string(TISSUE_TEST_CONFIG_DIR) + "/lung_small.json");
  const core::Geometry g = core::build_geometry(c);
  const LrpimCaseRun run = run_lrpim_case(c, g, lung_options());
  std::cout << "LRPIM set-up " << run.setup_seconds << " s" << std::endl;
  const reference_fem::FemRunResult fem = reference_fem::run_case(c, g);
  const Score s = score(run.sample_displacements, fem.sample_displacements);
  print_run("lung_small", run, s);
  for (Eigen::Index i = 0; i < fem.sample_displacements.rows(); ++i)
    std::cout << "  sample " << i << ": FEM " << fem.sample_displacements.row(i) * 1e3 << " mm, LRPIM "
              << run.sample_displacements.row(i) * 1e3 << " mm\n";
  EXPECT_LT(s.rmse / s.peak, 0.05);
  EXPECT_NEAR(run.details["load"]["total_force_n"][0].get<double>(), c.load.force.x(), 1e-12);
}

// The CI-sized lung (16 mm cloud): a quick run for trying solver options (LRPIM_KRYLOV_OPTIONS); disabled.
TEST(LrpimLung, DISABLED_LungSmallCiRuns) {
  const core::Case c = core::load_case(std::string(TISSUE_TEST_CONFIG_DIR) + "/ci/lung_small_ci.json");
  core::GeometryOptions geometry;
  geometry.build_fem_mesh = false;
  const core::Geometry g = core::build_geometry(c, geometry);
  const LrpimCaseRun run = run_lrpim_case(c, g, lung_options());
  std::cout << run.details.dump() << "\n" << run.sample_displacements * 1e3 << "\n";
}

// The angular rule's effect on lung_small (docs/LRPIM.md §5): run with --gtest_also_run_disabled_tests.
TEST(LrpimLung, DISABLED_AngularRuleStudyOnLungSmall) {
  const core::Case c = core::load_case(std::string(TISSUE_TEST_CONFIG_DIR) + "/lung_small.json");
  const core::Geometry g = core::build_geometry(c);
  const reference_fem::FemRunResult fem = reference_fem::run_case(c, g);
  for (const auto& [polar, azimuthal, radial] : std::vector<std::tuple<int, int, int>>{{4, 8, 3}, {6, 12, 3}, {8, 16, 4}}) {
    LrpimCaseOptions options = lung_options();
    options.rule.polar = polar;
    options.rule.azimuthal = azimuthal;
    options.rule.radial = radial;
    const LrpimCaseRun run = run_lrpim_case(c, g, options);
    print_run("rule " + std::to_string(polar) + " x " + std::to_string(azimuthal) + " x " + std::to_string(radial), run,
              score(run.sample_displacements, fem.sample_displacements));
  }
}

// Disabled for the same reason as the lung_small comparison above.
TEST(LrpimLung, DISABLED_RealStlLobeRunsAndConverges) {
  const std::string config = std::string(TISSUE_TEST_CONFIG_DIR) + "/lung_stl.json";
  const core::Case c = core::load_case(config);
  if (!std::filesystem::exists(c.geometry.stl_file))
    GTEST_SKIP() << "no " << c.geometry.stl_file << " (../shared/data/lung is absent); nothing to run";
  core::GeometryOptions geometry;
  geometry.build_fem_mesh = false;
  const core::Geometry g = core::build_geometry(c, geometry);
  const LrpimCaseRun run = run_lrpim_case(c, g, lung_options());
  ASSERT_EQ(static_cast<int>(run.steps.size()), c.time.steps);
  ASSERT_TRUE(run.sample_displacements.allFinite());
  double peak = 0.0;
  for (Eigen::Index i = 0; i < run.sample_displacements.rows(); ++i) peak = std::max(peak, run.sample_displacements.row(i).norm());
  std::cout << "lung_stl: " << run.n_nodes << " nodes, largest sample displacement " << peak * 1e3 << " mm, "
            << run.details.dump() << "\n";
  EXPECT_GT(peak, 0.3e-3);
  EXPECT_LT(peak, 30e-3);
  EXPECT_GT(run.sample_displacements(0, 0) * c.load.force.x(), 0.0);  // the nearest sample moves with the force
}

}  // namespace
}  // namespace meshless::lrpim
