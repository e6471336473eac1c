// EFG linear solvers: the automatic direct/iterative choice from UMFPACK's symbolic estimate, and the
// iterative fallback (Jacobi-BiCGSTAB) reaching the same equilibrium as the sparse LU.
#include <gtest/gtest.h>

#include <iostream>
#include <vector>

#include "meshless/direct_solver_estimate.hpp"
#include "meshless/efg_model.hpp"
#include "meshless/verification_problems.hpp"

namespace meshless {
namespace {

Eigen::VectorXd solve_sheared_box(int side, LinearSolverKind solver, EfgStatistics* stats = nullptr) {
  EfgOptions options;
  options.linear_solver = solver;
  EfgModel model(sheared_box_problem(side), options);
  model.setup_system();
  const StepRecord r = model.solve_step(1);
  EXPECT_LE(r.residuals.back(), 1e-8);  // solve_step throws when Newton fails
  if (stats) *stats = model.statistics();
  return model.nodal_parameters();
}

TEST(EfgLinearSolvers, AutomaticChoiceFactorisesSmallCloudsAndReportsTheEstimate) {
  EfgStatistics small, larger;
  solve_sheared_box(5, LinearSolverKind::automatic, &small);
  solve_sheared_box(8, LinearSolverKind::automatic, &larger);
  std::cout << "LU estimates (AMD, blocked): 5^3 nodes " << small.direct_peak_memory_estimate / 1e6 << " MB, "
            << small.direct_flops_estimate / 1e6 << " Mflop; 8^3 nodes " << larger.direct_peak_memory_estimate / 1e6
            << " MB, " << larger.direct_flops_estimate / 1e6 << " Mflop\n";
  EXPECT_EQ(small.linear_solver.rfind("UMFPACK", 0), 0u);
  // The peak memory is at least the matrix (8-byte values + 4-byte indices) and grows with the cloud.
  EXPECT_GT(small.direct_peak_memory_estimate, 12.0 * small.matrix_nonzeros);
  EXPECT_GT(larger.direct_peak_memory_estimate, small.direct_peak_memory_estimate);
  EXPECT_GT(larger.direct_flops_estimate, small.direct_flops_estimate);
  EXPECT_GT(physical_memory_bytes(), 1e8);
}

TEST(EfgLinearSolvers, IterativeFallbackReachesTheDirectSolution) {
  EfgStatistics iterative_stats;
  const Eigen::VectorXd direct = solve_sheared_box(6, LinearSolverKind::direct);
  const Eigen::VectorXd iterative = solve_sheared_box(6, LinearSolverKind::iterative, &iterative_stats);
  const double difference = (iterative - direct).norm() / direct.norm();
  std::cout << "6^3 sheared box: |U| = " << direct.norm() * 1e3 << " mm, BiCGSTAB vs UMFPACK relative difference "
            << difference << "\n";
  EXPECT_EQ(iterative_stats.linear_solver.rfind("BiCGSTAB", 0), 0u);
  EXPECT_GT(direct.norm(), 0.0);
  EXPECT_LT(difference, 1e-6);
}

/// The node-pair pattern of a 27-point stencil on an n^3 grid, and the same pattern expanded to 3 x 3 blocks.
UmfpackMatrix grid_pattern(int n, int block) {
  std::vector<Eigen::Triplet<double, long>> entries;
  auto id = [n](int x, int y, int z) { return (static_cast<long>(z) * n + y) * n + x; };
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x)
        for (int dz = -1; dz <= 1; ++dz)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
              const int X = x + dx, Y = y + dy, Z = z + dz;
              if (X < 0 || Y < 0 || Z < 0 || X >= n || Y >= n || Z >= n) continue;
              for (int a = 0; a < block; ++a)
                for (int b = 0; b < block; ++b)
                  entries.emplace_back(block * id(x, y, z) + a, block * id(X, Y, Z) + b, 1.0);
            }
  UmfpackMatrix m(block * n * n * n, block * n * n * n);
  m.setFromTriplets(entries.begin(), entries.end());
  return m;
}

TEST(EfgLinearSolvers, BlockedEstimateMatchesTheFullAnalysis) {
  const DirectSolverEstimate full = estimate_direct_solver(grid_pattern(12, 3));
  const DirectSolverEstimate blocked = estimate_direct_solver_blocked(grid_pattern(12, 1), 3);
  std::cout << "12^3 grid, 3 DOFs per node: peak memory " << full.peak_memory_bytes / 1e6 << " MB (full) vs "
            << blocked.peak_memory_bytes / 1e6 << " MB (blocked), flops " << full.factorisation_flops / 1e9 << " vs "
            << blocked.factorisation_flops / 1e9 << " Gflop\n";
  EXPECT_GT(blocked.peak_memory_bytes, 0.5 * full.peak_memory_bytes);
  EXPECT_LT(blocked.peak_memory_bytes, 2.0 * full.peak_memory_bytes);
  // An estimate for a yes/no memory decision: memory within 2x, flops within 4x (UMFPACK counts the zeros
  // its relaxed supernodes carry; AMD counts exact fill).
  EXPECT_GT(blocked.factorisation_flops, 0.25 * full.factorisation_flops);
  EXPECT_LT(blocked.factorisation_flops, 4.0 * full.factorisation_flops);
}

TEST(EfgLinearSolvers, EstimateRejectsAnUncompressedMatrix) {
  UmfpackMatrix a(3, 3);
  a.insert(0, 0) = 1.0;  // insert leaves the matrix uncompressed
  EXPECT_THROW(estimate_direct_solver(a), std::invalid_argument);
}

}  // namespace
}  // namespace meshless
