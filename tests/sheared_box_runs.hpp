#pragma once
// The sheared box of the EFG solver tests (meshless::sheared_box_problem), stepped to the end: shared by the suites
// that compare the linear solvers on one process (test_efg_linear_solvers) and over two (test_efg_mpi).
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <utility>

#include "meshless/efg/efg_model.hpp"
#include "meshless/verification/verification_problems.hpp"

namespace meshless {

/// The parameters U after the last of `steps` steps of 0.1 s on the sheared box (material k as given; the first
/// step elastic, then creep), each checked to have met Newton's tolerance.
inline Eigen::VectorXd solve_sheared_box(int side, LinearSolverKind solver, EfgStatistics* stats = nullptr,
                                         double k = 0.0, int steps = 1, int* krylov_iterations = nullptr) {
  EfgOptions options;
  options.linear_solver = solver;
  // The runs compare linear solvers: the direct one factorises the tangent itself, exactly.
  options.direct_symmetric_part = false;
  EfgProblem problem = sheared_box_problem(side);
  problem.material.k = k;
  problem.step_times.clear();
  for (int s = 0; s < steps; ++s) problem.step_times.push_back(0.1 * s);
  EfgModel model(std::move(problem), options);
  model.setup_system();
  int iterations = 0;
  for (int s = 1; s <= steps; ++s) {
    const StepRecord r = model.solve_step(s);
    EXPECT_LE(r.residuals.back(), 1e-8);  // solve_step throws when Newton fails
    iterations += r.linear_iterations;
  }
  if (stats) *stats = model.statistics();
  if (krylov_iterations) *krylov_iterations = iterations;
  return model.nodal_parameters();
}

}  // namespace meshless
