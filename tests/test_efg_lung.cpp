// Smoke run of the EFG model on the built-in lung (configs/ci/lung_small_ci.json, the CI-sized lung_small): the whole load case runs, every
// step's Newton iteration converges, nothing is NaN, and the sample points move by a few millimetres.
#include <gtest/gtest.h>

#include <iostream>

#include "core/case.hpp"
#include "core/geometry.hpp"
#include "meshless/efg/efg_model.hpp"

namespace meshless {
namespace {

TEST(EfgLung, SmallCaseRunsAndConverges) {
  core::Case c = core::load_case(std::string(TISSUE_TEST_CONFIG_DIR) + "/ci/lung_small_ci.json");
  // Two steps (ramp to full load at t = 1 s) keep the smoke run short.
  c.time.total = 1.0;
  c.time.steps = 2;
  core::GeometryOptions options;
  options.build_fem_mesh = false;
  const core::Geometry g = core::build_geometry(c, options);
  EfgModel model(problem_from_case(c, g));
  model.run();
  const EfgStatistics& st = model.statistics();
  std::cout << "lung_small: " << st.num_nodes << " nodes, " << st.num_volume_points << " volume points, alpha "
            << st.alpha << " Pa/m, load area " << st.loaded_area * 1e6 << " mm^2\n";
  ASSERT_EQ(model.steps().size(), static_cast<size_t>(c.time.steps));
  for (const StepRecord& s : model.steps()) {
    EXPECT_LE(s.residuals.back(), model.options().newton_tolerance) << "step " << s.step;
    EXPECT_GE(s.newton_iterations, 1);
    // Measured 8 and 11: the kept factors of the first tangent contract the residual by 0.13-0.26 per iteration,
    // above the 0.5 that would refresh them (EfgOptions::refactor_contraction).
    EXPECT_LE(s.newton_iterations, 12) << "step " << s.step;
    std::cout << "step " << s.step << " t = " << s.time << ": " << s.newton_iterations << " Newton iterations, residuals";
    for (double r : s.residuals) std::cout << " " << r;
    std::cout << "\n";
  }
  const core::PointMatrix u = model.displacements_at(g.sample_points);
  ASSERT_TRUE(u.allFinite());
  double max_mm = 0.0;
  for (Eigen::Index i = 0; i < u.rows(); ++i) {
    std::cout << "sample " << i << ": |u| = " << u.row(i).norm() * 1e3 << " mm\n";
    max_mm = std::max(max_mm, u.row(i).norm() * 1e3);
  }
  EXPECT_GT(max_mm, 0.3);
  EXPECT_LT(max_mm, 30.0);
  // The load pushes along +x (force [0.3, 0, 0]): the nearest samples must move that way.
  EXPECT_GT(u.col(0).maxCoeff(), 0.0);
}

}  // namespace
}  // namespace meshless
