// Smoke test of the FEM reference on the built-in lung (configs/ci/lung_small_ci.json, the CI-sized lung_small, paper §5.4): Newton
// converges at every step, the sample displacements are finite and a few millimetres.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "core/case.hpp"
#include "core/geometry.hpp"
#include "reference_fem/fem_model.hpp"

namespace reference_fem {
namespace {

TEST(FemLung, SmallCaseConvergesWithMillimetreDisplacements) {
  core::Case c = core::load_case(std::string(TISSUE_TEST_CONFIG_DIR) + "/ci/lung_small_ci.json");
  core::GeometryOptions options;
  options.build_node_cloud = false;
  const core::Geometry g = core::build_geometry(c, options);
  const FemRunResult r = run_case(c, g);
  ASSERT_EQ(static_cast<int>(r.steps.size()), c.time.steps);
  for (const auto& s : r.steps) {
    EXPECT_GE(s.newton_iterations, 1);
    EXPECT_LE(s.newton_iterations, 6);  // quadratic convergence of the consistent tangent
    EXPECT_LE(s.residuals.back(), c.fem.newton_tolerance);
  }
  ASSERT_TRUE(r.sample_displacements.allFinite());
  const double u0 = r.sample_displacements.row(0).norm();
  std::cout << "dofs " << r.n_dofs << " sample 0 displacement " << u0 * 1e3 << " mm\n";
  EXPECT_GT(u0, 0.5e-3);
  EXPECT_LT(u0, 30e-3);
  // The load pushes along +x (into the lobe from the lateral side): the sample nearest the load moves with it.
  EXPECT_GT(r.sample_displacements(0, 0) * c.load.force.x(), 0.0);
  // Creep: the ramp ends at t = 1 s and the load is held to 2 s, so the displacement keeps growing.
  const Eigen::Index mid = c.time.steps / 2 - 1;
  EXPECT_GT(r.sample_history.back().row(0).norm(), r.sample_history[mid].row(0).norm());
}

}  // namespace
}  // namespace reference_fem
