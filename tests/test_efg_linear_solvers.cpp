// EFG linear solvers: the automatic direct/iterative choice from the LU estimate and the available memory,
// the two sparse LUs (MUMPS, UMFPACK) and the iterative solvers (a Krylov method through PETSc,
// Jacobi-BiCGSTAB) reaching the same equilibrium, with the symmetric (k = 0) and the non-symmetric (k != 0) tangent.
#include <deal.II/base/mpi.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <iostream>
#include <sstream>
#include <vector>

#include "core/mpi_session_directory.hpp"
#include "meshless/solvers/petsc_krylov_solver.hpp"
#include "meshless/solvers/anderson_acceleration.hpp"
#include "meshless/solvers/available_memory.hpp"
#include "meshless/solvers/direct_solver_estimate.hpp"
#include "meshless/efg/efg_model.hpp"
#include "meshless/solvers/mumps_lu.hpp"
#include "meshless/verification/verification_problems.hpp"
#include "tests/sheared_box_runs.hpp"

namespace meshless {
namespace {

TEST(EfgLinearSolvers, AutomaticChoiceFactorisesSmallCloudsAndReportsTheEstimate) {
  EfgStatistics small, larger;
  solve_sheared_box(5, LinearSolverKind::automatic, &small);
  solve_sheared_box(8, LinearSolverKind::automatic, &larger);
  std::cout << "LU estimates (AMD, blocked): 5^3 nodes " << small.direct_peak_memory_estimate / 1e6 << " MB, "
            << small.direct_flops_estimate / 1e6 << " Mflop; 8^3 nodes " << larger.direct_peak_memory_estimate / 1e6
            << " MB, " << larger.direct_flops_estimate / 1e6 << " Mflop\n";
  EXPECT_EQ(small.linear_solver.rfind("MUMPS", 0), 0u);
  // The peak memory is at least the matrix (8-byte values + 4-byte indices) and grows with the cloud.
  EXPECT_GT(small.direct_peak_memory_estimate, 12.0 * small.matrix_nonzeros);
  EXPECT_GT(larger.direct_peak_memory_estimate, small.direct_peak_memory_estimate);
  EXPECT_GT(larger.direct_flops_estimate, small.direct_flops_estimate);
  // The budget is the memory available now: positive, and below the physical memory.
  EXPECT_GT(small.available_memory, 1e8);
  EXPECT_LT(small.available_memory, static_cast<double>(sysconf(_SC_PHYS_PAGES)) * sysconf(_SC_PAGE_SIZE));
}

TEST(EfgLinearSolvers, AutomaticChoiceFallsBackOnTheKrylovSolverWhenTheLuDoesNotFit) {
  EfgOptions options;
  options.direct_solver_memory_fraction = 1e-9;  // no LU fits: the PETSc Krylov solve
  EfgModel model(sheared_box_problem(5), options);
  model.setup_system();
  const StepRecord r = model.solve_step(1);
  EXPECT_EQ(model.statistics().linear_solver.rfind("PETSc lgmres + eisenstat", 0), 0u)
      << model.statistics().linear_solver;
  EXPECT_GT(r.linear_iterations, 0);
  EXPECT_LE(r.residuals.back(), 1e-8);
}

TEST(EfgLinearSolvers, AvailableMemoryIsReadFromThisMachine) {
  const AvailableMemory m = available_memory();
  std::ifstream meminfo("/proc/meminfo");
  std::stringstream text;
  text << meminfo.rdbuf();
  const std::optional<double> mem_available = parse_mem_available(text.str());
  const double physical = static_cast<double>(sysconf(_SC_PHYS_PAGES)) * sysconf(_SC_PAGE_SIZE);
  std::cout << "available memory " << m.bytes / 1e9 << " GB from " << m.source << "; MemAvailable "
            << (mem_available ? *mem_available / 1e9 : -1.0) << " GB; physical " << physical / 1e9 << " GB\n";
  ASSERT_TRUE(mem_available.has_value());  // Linux: /proc/meminfo always has it
  EXPECT_GT(m.bytes, 1e8);
  EXPECT_LE(m.bytes, physical);
  EXPECT_FALSE(m.source.empty());
  // Never above what the kernel says is available (a cgroup limit only lowers it); the two reads are moments
  // apart, so allow 5 % for other processes.
  EXPECT_LE(m.bytes, 1.05 * *mem_available);
  if (m.source.rfind("MemAvailable", 0) == 0) EXPECT_NEAR(m.bytes, *mem_available, 0.05 * *mem_available);
}

TEST(EfgLinearSolvers, MemoryTextsAreParsed) {
  EXPECT_DOUBLE_EQ(*parse_mem_available("MemTotal:       24684096 kB\nMemFree: 1 kB\nMemAvailable:   22391680 kB\n"),
                   22391680.0 * 1024.0);
  EXPECT_FALSE(parse_mem_available("MemTotal: 5 kB\n").has_value());
  EXPECT_FALSE(parse_mem_available("MemAvailable: lots\n").has_value());
  const double physical = 24e9;
  EXPECT_DOUBLE_EQ(*cgroup_headroom("4294967296\n", "1073741824\n", physical), 3221225472.0);  // v2 or v1 limit
  EXPECT_FALSE(cgroup_headroom("max\n", "1073741824\n", physical).has_value());                 // v2: no limit
  EXPECT_FALSE(cgroup_headroom("9223372036854771712\n", "3388674048\n", physical).has_value());  // v1: no limit
  EXPECT_DOUBLE_EQ(*cgroup_headroom("1000\n", "2000\n", physical), 0.0);                          // over the limit
  EXPECT_FALSE(cgroup_headroom("", "1\n", physical).has_value());
}

/// Each iterative solver against the direct solver (MUMPS) on the 6^3 box, k = 0 (one elastic step) and k = 2 (a non-symmetric
/// tangent that changes with the strain: an elastic step and two creep steps, several Newton iterations each).
void expect_iterative_matches_direct(LinearSolverKind solver, const std::string& label, double k, int steps,
                                     double tolerance) {
  EfgStatistics stats;
  int iterations = 0;
  const Eigen::VectorXd direct = solve_sheared_box(6, LinearSolverKind::direct, nullptr, k, steps);
  const Eigen::VectorXd iterative = solve_sheared_box(6, solver, &stats, k, steps, &iterations);
  const double difference = (iterative - direct).norm() / direct.norm();
  std::cout << "6^3 sheared box, k = " << k << ": |U| = " << direct.norm() * 1e3 << " mm; " << stats.linear_solver
            << ": " << iterations << " Krylov iterations, relative difference to the LU " << difference << "\n";
  EXPECT_EQ(stats.linear_solver.rfind(label, 0), 0u) << stats.linear_solver;
  EXPECT_GT(direct.norm(), 1e-4);
  EXPECT_GT(iterations, 0);
  EXPECT_LT(difference, tolerance);
}

TEST(EfgLinearSolvers, KrylovReachesTheDirectSolutionWithKZero) {
  // One Newton iteration on a solve to a relative residual of 1e-9; the tangent's small eigenvalues leave a larger
  // error in the parameters: measured 2.2e-9.
  expect_iterative_matches_direct(LinearSolverKind::petsc_krylov, "PETSc lgmres + eisenstat", 0.0, 1, 5e-9);
}

TEST(EfgLinearSolvers, KrylovReachesTheDirectSolutionWithNonzeroK) {
  // Both stop at Newton's tolerance, by different Newton paths (the LU run solves some tangents by GMRES on
  // earlier factors): measured 1.2e-11.
  expect_iterative_matches_direct(LinearSolverKind::petsc_krylov, "PETSc lgmres + eisenstat", 2.0, 3, 1e-10);
}

TEST(EfgLinearSolvers, GmresOnEarlierFactorsReachesTheSameEquilibriumWithFewerFactorisations) {
  // k = 2 over an elastic and two creep steps: the tangent changes every Newton iteration. Factorising each
  // refreshed tangent and solving it by GMRES on the kept factors must end at the same equilibrium (both stop
  // at Newton's tolerance); the second factorises less.
  auto run = [](int earlier_factors_max_iterations, int* factorisations, int* krylov) {
    EfgOptions options;
    options.linear_solver = LinearSolverKind::direct;
    options.earlier_factors_max_iterations = earlier_factors_max_iterations;
    options.anderson_depth = 0;  // the same path in both runs apart from the solver: the difference is round-off
    options.extrapolate_start = false;
    options.gmres_forcing = 0.0;  // GMRES as exact as the factors (the test below looks at the forcing)
    EfgProblem problem = sheared_box_problem(6);
    problem.material.k = 2.0;
    problem.step_times = {0.0, 0.1, 0.2};
    EfgModel model(std::move(problem), options);
    model.setup_system();
    *factorisations = *krylov = 0;
    for (int s = 1; s <= 3; ++s) {
      const StepRecord r = model.solve_step(s);
      EXPECT_LE(r.residuals.back(), 1e-8);
      *factorisations += r.factorisations;
      *krylov += r.linear_iterations;
    }
    return model.nodal_parameters();
  };
  int lu_factorisations = 0, lu_krylov = 0, gmres_factorisations = 0, gmres_krylov = 0;
  const Eigen::VectorXd factorising = run(0, &lu_factorisations, &lu_krylov);
  const Eigen::VectorXd on_earlier_factors = run(30, &gmres_factorisations, &gmres_krylov);
  const double difference = (on_earlier_factors - factorising).norm() / factorising.norm();
  std::cout << "6^3 sheared box, k = 2, three steps: " << lu_factorisations << " factorisations when each refreshed "
            << "tangent is factorised; " << gmres_factorisations << " and " << gmres_krylov
            << " GMRES iterations on earlier factors; relative difference " << difference << "\n";
  EXPECT_EQ(lu_krylov, 0);
  EXPECT_GT(gmres_krylov, 0);
  EXPECT_EQ(gmres_factorisations, 1);  // the first elastic tangent only
  EXPECT_GE(lu_factorisations, 2);  // measured: 2
  EXPECT_LT(difference, 1e-10);
}

TEST(EfgLinearSolvers, GmresForcingStopsEarlierAndReachesTheSameEquilibrium) {
  // The GMRES solves on earlier factors stop at EfgOptions::gmres_forcing times Newton's relative residual (or at
  // what Newton still needs), not at iterative_tolerance: fewer GMRES iterations, the same equilibrium to within
  // what Newton's tolerance (1e-8 of the load) allows.
  auto run = [](double forcing, int* krylov, int* newton) {
    EfgOptions options;
    options.linear_solver = LinearSolverKind::direct;
    options.gmres_forcing = forcing;
    EfgProblem problem = sheared_box_problem(6);
    problem.material.k = 2.0;
    problem.step_times = {0.0, 0.1, 0.2, 0.3, 0.4};
    EfgModel model(std::move(problem), options);
    model.setup_system();
    *krylov = *newton = 0;
    for (int s = 1; s <= 5; ++s) {
      const StepRecord r = model.solve_step(s);
      EXPECT_LE(r.residuals.back(), 1e-8);
      *krylov += r.linear_iterations;
      *newton += r.newton_iterations;
    }
    return model.nodal_parameters();
  };
  int exact_krylov = 0, exact_newton = 0, forced_krylov = 0, forced_newton = 0;
  const Eigen::VectorXd exact = run(0.0, &exact_krylov, &exact_newton);
  const Eigen::VectorXd forced = run(0.1, &forced_krylov, &forced_newton);
  const double difference = (forced - exact).norm() / exact.norm();
  std::cout << "6^3 sheared box, k = 2, five steps: " << exact_krylov << " GMRES iterations (" << exact_newton
            << " Newton) to iterative_tolerance, " << forced_krylov << " (" << forced_newton
            << " Newton) with forcing 0.1; relative difference " << difference << "\n";
  // Measured: 47 GMRES iterations against 18, 13 Newton iterations each, difference 1.0e-11.
  EXPECT_LT(2 * forced_krylov, exact_krylov);
  EXPECT_LE(forced_newton, exact_newton + 1);
  EXPECT_LT(difference, 1e-10);
}

TEST(EfgLinearSolvers, TheTangentAppliedPointByPointEqualsTheAssembledMatrix) {
  // GMRES on kept factors applies a refreshed tangent without assembling it (EfgModel::apply_tangent): the same
  // sums as the matrix (eq. 21 with VCI's test gradients, and the penalty of eq. 23), in another order. Checked at a
  // deformed state with history (k = 2, two steps), where the law's tangent is unsymmetric.
  EfgOptions options;
  options.linear_solver = LinearSolverKind::direct;
  EfgProblem problem = sheared_box_problem(6);
  problem.material.k = 2.0;
  problem.step_times = {0.1, 0.2};
  EfgModel model(std::move(problem), options);
  model.setup_system();
  model.solve_step(1);
  model.solve_step(2);
  model.assemble_system(true);
  double worst = 0.0;
  for (int trial = 0; trial < 3; ++trial) {
    const Eigen::VectorXd v = trial == 0 ? Eigen::VectorXd(model.nodal_parameters())
                                         : Eigen::VectorXd(Eigen::VectorXd::Random(model.nodal_parameters().size()));
    const Eigen::VectorXd assembled = model.system_matrix() * v;
    Eigen::VectorXd by_points;
    model.apply_tangent(v, &by_points);
    worst = std::max(worst, (by_points - assembled).norm() / assembled.norm());
  }
  std::cout << "6^3 sheared box, k = 2, after two steps: the tangent applied point by point against the assembled "
               "matrix, largest relative difference "
            << worst << "\n";
  // Measured: 1.06e-13, the round-off of the penalty's large terms summed in another order. A missing VCI
  // correction or penalty term would differ by orders of magnitude more.
  EXPECT_LT(worst, 1e-12);
}

TEST(EfgLinearSolvers, KeptFactorsGiveWayWhenTheirRateCannotReachTheToleranceInTime) {
  // k = 2: the kept factors of the first tangent contract the residual slowly. With a refresh rule that never
  // fires on the rate alone (0.99) and an iteration limit of 8, only the projection (iterations left at the
  // observed rate) can refresh the tangent in time. Measured: the first step's kept factors contract by 0.14, so 9.4
  // iterations would be needed; with the projection Newton refreshes and every step converges in 3.
  EfgOptions options;
  options.linear_solver = LinearSolverKind::direct;
  options.refactor_contraction = 0.99;
  options.max_newton_iterations = 8;
  EfgProblem problem = sheared_box_problem(6);
  problem.material.k = 2.0;
  problem.step_times = {0.0, 0.1, 0.2};
  EfgModel model(std::move(problem), options);
  model.setup_system();
  int refresh_work = 0;  // factorisations and GMRES iterations on earlier factors
  for (int s = 1; s <= 3; ++s) {
    const StepRecord r = model.solve_step(s);
    EXPECT_EQ(r.cutbacks, 0) << "step " << s;
    EXPECT_LE(r.residuals.back(), 1e-8) << "step " << s;
    std::cout << "step " << s << ", ||R|| / ||F||:";
    for (double x : r.residuals) std::cout << " " << x;
    std::cout << "\n";
    refresh_work += r.linear_iterations + r.factorisations;
  }
  EXPECT_GT(refresh_work, 1);  // more than the first factorisation: a refreshed tangent was solved
}

TEST(AndersonAcceleration, SolvesALinearFixedPointInDimensionPlusOneIterations) {
  // u <- u + M^-1 (b - A u) with M = diag(A), a stale "tangent" whose iteration contracts by about 0.6. On a
  // linear map of dimension n, Anderson with depth >= n is GMRES in disguise (Walker & Ni 2011, Theorem 2.2):
  // exact after n + 1 updates. Plain iteration needs tens.
  Eigen::Matrix4d a;
  a << 4, 1, 0.5, 0, 1, 3, 1, 0.2, 0.5, 1, 3, 1, 0, 0.2, 1, 2;
  const Eigen::Vector4d b(1, -2, 0.5, 3);
  const Eigen::Vector4d solution = a.partialPivLu().solve(b);
  auto iterations_to = [&](int depth, double tolerance) {
    AndersonAcceleration mixing(depth);
    Eigen::VectorXd u = Eigen::VectorXd::Zero(4);
    for (int it = 1; it <= 200; ++it) {
      const Eigen::VectorXd f = ((b - a * u).array() / a.diagonal().array()).matrix();
      u += mixing.next_update(u, f);
      if ((u - solution).norm() <= tolerance * solution.norm()) return it;
    }
    return 201;
  };
  const int plain = iterations_to(0, 1e-10), mixed = iterations_to(5, 1e-10), shallow = iterations_to(2, 1e-10);
  std::cout << "iterations to 1e-10: plain " << plain << ", depth 2 " << shallow << ", depth 5 " << mixed << "\n";
  EXPECT_LE(mixed, 5);    // n + 1 = 5
  EXPECT_GE(plain, 45);   // measured 51 (depth 2: 17)
  EXPECT_LT(shallow, plain);
  AndersonAcceleration off(0);
  const Eigen::VectorXd f = Eigen::VectorXd::Constant(3, 0.25);
  EXPECT_EQ(off.next_update(Eigen::VectorXd::Zero(3), f), f);
  EXPECT_THROW(AndersonAcceleration(-1), std::invalid_argument);
}

TEST(EfgLinearSolvers, PredictorAndAndersonMixingReachTheSameEquilibriumInFewerIterations) {
  // k = 2, a ramp over three steps and a hold over two: the kept factors of the first tangent contract slowly
  // (about 0.14 per iteration, the test above). The extrapolated start and the mixed updates change the path,
  // never the equilibrium: both runs stop at Newton's tolerance, at the same parameters.
  auto run = [](bool accelerated, int* iterations) {
    EfgOptions options;
    options.linear_solver = LinearSolverKind::direct;
    options.anderson_depth = accelerated ? 5 : 0;
    options.extrapolate_start = accelerated;
    EfgProblem problem = sheared_box_problem(6);
    problem.material.k = 2.0;
    problem.step_times = {0.1, 0.2, 0.3, 0.4, 0.5};
    problem.load_scale = [](double t) { return std::min(t / 0.3, 1.0); };
    EfgModel model(std::move(problem), options);
    model.setup_system();
    *iterations = 0;
    for (int s = 1; s <= 5; ++s) {
      const StepRecord r = model.solve_step(s);
      EXPECT_LE(r.residuals.back(), 1e-8) << "step " << s;
      EXPECT_TRUE(r.retried_plain.empty()) << "step " << s;
      EXPECT_EQ(r.cutbacks, 0) << "step " << s;
      *iterations += r.newton_iterations;
    }
    return model.nodal_parameters();
  };
  int plain_iterations = 0, accelerated_iterations = 0;
  const Eigen::VectorXd plain = run(false, &plain_iterations);
  const Eigen::VectorXd accelerated = run(true, &accelerated_iterations);
  const double difference = (accelerated - plain).norm() / plain.norm();
  std::cout << "6^3 sheared box, k = 2, five steps: " << plain_iterations << " Newton iterations plain, "
            << accelerated_iterations << " with the predictor and Anderson mixing; relative difference " << difference
            << "\n";
  EXPECT_LT(difference, 1e-8);
  EXPECT_GE(plain_iterations, 25);        // measured 25 (24 on the LU of the tangent itself)
  EXPECT_LE(accelerated_iterations, 20);  // measured 20 (19 on the LU)
}

TEST(PetscKrylovSolver, TheOptionsStringReachesTheMultigridLevels) {
  // PETSc creates the level smoothers inside the preconditioner and reads their options ("-mg_levels_...")
  // from its default database: the solver's own options string must reach them too.
  EfgModel model(sheared_box_problem(8));
  model.setup_system();
  model.assemble_system(true);
  const SparseMatrix& a = model.system_matrix();
  const Eigen::VectorXd b = a * Eigen::VectorXd::Ones(a.rows());
  const std::string ml = "-ksp_type fgmres -ksp_gmres_restart 200 -pc_type ml ";
  auto iterations = [&](const std::string& options) {
    PetscKrylovSolver solver(model.nodes(), options, 1e-9, 5000);
    solver.set_matrix(a);
    const Eigen::VectorXd x = solver.solve(b);
    EXPECT_LT((a * x - b).norm(), 1e-8 * b.norm()) << options;
    return solver.last_iterations();
  };
  const int richardson = iterations(ml);
  const int krylov_smoother = iterations(ml + "-mg_levels_ksp_type gcr -mg_levels_ksp_max_it 10");
  std::cout << "8^3 sheared box, ML: " << richardson << " iterations with one SOR sweep per level, "
            << krylov_smoother << " with ten GCR iterations\n";
  EXPECT_LT(krylov_smoother * 10, richardson);  // measured: 269 against 19
  // A level option PETSc does not know is an error, not ignored.
  PetscKrylovSolver misspelt(model.nodes(), ml + "-mg_levels_ksp_type no_such_method", 1e-9, 5000);
  EXPECT_THROW(misspelt.set_matrix(a), std::runtime_error);
}

TEST(PetscKrylovSolver, ASparserPreconditionerMatrixKeepsTheSolutionAndTheIterations) {
  // The preconditioner built from the tangent without its small off-node entries (EfgOptions::
  // preconditioner_drop_tolerance): the Krylov method still applies the whole tangent, so the solution is
  // the same; the hierarchy and the SOR sweeps read a quarter of the entries.
  EfgModel model(sheared_box_problem(10));
  model.setup_system();
  model.assemble_system(true);
  const SparseMatrix& a = model.system_matrix();
  const Eigen::VectorXd b = a * Eigen::VectorXd::Ones(a.rows());
  const std::string options = kMlWithGcrSmoothersOptions;
  PetscKrylovSolver whole(model.nodes(), options, 1e-10, 5000, 0.0);
  whole.set_matrix(a);
  const Eigen::VectorXd x_whole = whole.solve(b);
  PetscKrylovSolver sparser(model.nodes(), options, 1e-10, 5000, 0.01);
  sparser.set_matrix(a);
  const Eigen::VectorXd x_sparser = sparser.solve(b);
  std::cout << "10^3 sheared box: " << whole.last_iterations() << " iterations preconditioned from the tangent, "
            << sparser.last_iterations() << " from " << 100.0 * sparser.preconditioner_fill()
            << " % of its entries\n";
  EXPECT_EQ(whole.preconditioner_fill(), 1.0);
  EXPECT_LT(sparser.preconditioner_fill(), 0.3);  // measured 0.26 on this box (0.24 at 8k and 32k nodes)
  EXPECT_LT((a * x_sparser - b).norm(), 1e-10 * b.norm());
  // The exact solution is all ones. A relative residual of 1e-10 leaves an error of about 1e-6 in the parameters
  // (the tangent is nearly singular on rough parameter vectors, docs/MESHLESS.md §2), with either matrix alike.
  const Eigen::VectorXd exact = Eigen::VectorXd::Ones(a.rows());
  const double error_whole = (x_whole - exact).norm() / exact.norm();
  const double error_sparser = (x_sparser - exact).norm() / exact.norm();
  std::cout << "relative error of the parameters: " << error_whole << " and " << error_sparser << "\n";
  EXPECT_LT(error_sparser, 3.0 * error_whole + 1e-12);
  EXPECT_LE(sparser.last_iterations(), whole.last_iterations() + 2);
  EXPECT_NE(sparser.description().find("% of the entries"), std::string::npos);
  EXPECT_THROW(PetscKrylovSolver(model.nodes(), options, 1e-9, 100, -0.1), std::invalid_argument);
}

TEST(PetscKrylovSolver, EisenstatSsorReachesTheToleranceInTheTrueResidual) {
  // The default options: LGMRES(100), left-preconditioned by SSOR through Eisenstat's trick. Left preconditioning
  // stops on the preconditioned residual, so check the true one; the iteration count catches a lost preconditioner
  // (unpreconditioned LGMRES does not reach 1e-9 here in 5,000 iterations).
  EfgModel model(sheared_box_problem(10));
  model.setup_system();
  model.assemble_system(true);
  const SparseMatrix& a = model.system_matrix();
  const Eigen::VectorXd exact = Eigen::VectorXd::Ones(a.rows());
  const Eigen::VectorXd b = a * exact;
  PetscKrylovSolver eisenstat(model.nodes(), EfgOptions{}.krylov_options, 1e-9, 5000);
  eisenstat.set_matrix(a);
  const Eigen::VectorXd x = eisenstat.solve(b);
  PetscKrylovSolver ml(model.nodes(), kMlWithGcrSmoothersOptions, 1e-9, 5000, 0.01);
  ml.set_matrix(a);
  const Eigen::VectorXd x_ml = ml.solve(b);
  const double residual = (a * x - b).norm() / b.norm();
  std::cout << "10^3 sheared box: " << eisenstat.description() << ": " << eisenstat.last_iterations()
            << " iterations, true relative residual " << residual
            << "; ML with GCR smoothers: " << ml.last_iterations()
            << " iterations; relative parameter errors " << (x - exact).norm() / exact.norm() << " and "
            << (x_ml - exact).norm() / exact.norm() << "\n";
  EXPECT_EQ(eisenstat.description(), "PETSc lgmres + eisenstat");
  EXPECT_LT(residual, 1e-9);
  EXPECT_LT(eisenstat.last_iterations(), 450);  // measured: 363
  // Both solutions are as far from the exact parameters as the tangent's small eigenvalues allow at this residual.
  EXPECT_LT((x - exact).norm() / exact.norm(), 3.0 * (x_ml - exact).norm() / exact.norm() + 1e-12);
}

TEST(PetscKrylovSolver, EisenstatRefusesOptionsItCannotServe) {
  EfgModel model(sheared_box_problem(4));
  const std::string options = EfgOptions{}.krylov_options;
  // A sparser preconditioner matrix would make Eisenstat's transformed operator the copy's, not the tangent's.
  try {
    PetscKrylovSolver solver(model.nodes(), options, 1e-9, 100, 0.01);
    FAIL() << "a drop tolerance with -pc_type eisenstat was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("preconditioner_drop_tolerance"), std::string::npos) << e.what();
  }
  // PETSc 3.18 crashes (SIGSEGV) in the Eisenstat preconditioner with a relaxation factor other than 1.
  try {
    PetscKrylovSolver solver(model.nodes(), options + " -pc_eisenstat_omega 1.2", 1e-9, 100);
    FAIL() << "-pc_eisenstat_omega 1.2 was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("-pc_sor_omega 1.2"), std::string::npos) << e.what();
  }
}

TEST(EfgLinearSolvers, JacobiBicgstabReachesTheDirectSolution) {
  expect_iterative_matches_direct(LinearSolverKind::jacobi_bicgstab, "BiCGSTAB", 0.0, 1, 1e-8);
}

TEST(EfgLinearSolvers, MumpsAndUmfpackReachTheSameEquilibriumWithNonzeroK) {
  // Both factorise exactly; the non-symmetric k = 2 tangent over an elastic and two creep steps (several Newton
  // iterations each, factorisations reused and refreshed) must end at the same parameters to round-off.
  EfgStatistics mumps, umfpack;
  const Eigen::VectorXd a = solve_sheared_box(6, LinearSolverKind::direct, &mumps, 2.0, 3);
  const Eigen::VectorXd b = solve_sheared_box(6, LinearSolverKind::direct_umfpack, &umfpack, 2.0, 3);
  const double difference = (a - b).norm() / b.norm();
  std::cout << "6^3 sheared box, k = 2: " << mumps.linear_solver << " against " << umfpack.linear_solver
            << ": relative difference " << difference << "\n";
  EXPECT_EQ(mumps.linear_solver.rfind("MUMPS", 0), 0u);
  EXPECT_EQ(umfpack.linear_solver.rfind("UMFPACK", 0), 0u);
  EXPECT_GT(b.norm(), 1e-4);
  EXPECT_LT(difference, 1e-13);  // measured: 2.3e-15 to 3.0e-15
}

/// A 4 x 4 non-symmetric system with a known solution, as the model's row-major matrix.
SparseMatrix small_unsymmetric_matrix() {
  Eigen::MatrixXd dense(4, 4);
  dense << 4, 1, 0, 0,  //
      2, 5, 1, 0,       //
      0, 3, 6, 1,       //
      1, 0, 2, 7;
  return dense.sparseView();
}

TEST(MumpsLu, SolvesAnUnsymmetricSystemAndReusesItsAnalysis) {
  MumpsLu lu("4x4");
  SparseMatrix a = small_unsymmetric_matrix();
  const Eigen::Vector4d x(1.0, -2.0, 3.0, 0.5);
  lu.factorise(a);
  EXPECT_LT((lu.solve(a * x) - x).norm(), 1e-14);
  EXPECT_GT(lu.factor_entries(), 0.0);
  // New values on the same pattern: the analysis is reused, the factors are new.
  a.coeffRef(2, 1) = -3.0;
  lu.factorise(a);
  EXPECT_LT((lu.solve(a * x) - x).norm(), 1e-14);
  // A matrix with spare room per row (uncompressed, as a cut body's) gives the same answer.
  SparseMatrix spare = a;
  spare.reserve(Eigen::VectorXi::Constant(4, 6));
  ASSERT_FALSE(spare.isCompressed());
  lu.factorise(spare);
  EXPECT_LT((lu.solve(a * x) - x).norm(), 1e-14);
}

TEST(MumpsLu, FactorisesTheSymmetricPartOfAStructurallySymmetricMatrix) {
  // symmetric_part: the factors are those of (A + A^T) / 2, whatever A's unsymmetric values (the EFG tangent's VCI
  // and k != 0 parts); a pattern without its transpose is refused, naming the entry.
  Eigen::MatrixXd dense(4, 4);
  dense << 4, 1, 0, 0.5,  //
      2, 5, 1, 0,         //
      0, 3, 6, 1,         //
      1, 0, 2, 7;
  SparseMatrix a = dense.sparseView();
  const Eigen::Vector4d b(1.0, -2.0, 3.0, 0.5);
  const Eigen::Vector4d expected = (0.5 * (dense + dense.transpose())).partialPivLu().solve(b);
  MumpsLu ldlt("4x4 symmetric part", 0.0, true);
  ldlt.factorise(a);
  EXPECT_LT((ldlt.solve(b) - expected).norm(), 1e-14 * expected.norm());
  SparseMatrix spare = a;  // spare room per row, as a cut body's matrix keeps
  spare.reserve(Eigen::VectorXi::Constant(4, 6));
  ldlt.factorise(spare);
  EXPECT_LT((ldlt.solve(b) - expected).norm(), 1e-14 * expected.norm());
  MumpsLu refuses("4x4 unsymmetric pattern", 0.0, true);
  try {
    refuses.factorise(small_unsymmetric_matrix());
    ADD_FAILURE() << "a pattern without its transpose was factorised";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("structurally symmetric pattern; (3, 0) has no (0, 3)"), std::string::npos)
        << e.what();
  }
}

TEST(MumpsLu, SaysWhyItFails) {
  Eigen::MatrixXd dense(3, 3);
  dense << 1, 2, 3,  //
      2, 4, 6,       //
      1, 0, 1;       // row 2 = 2 x row 1: numerically singular
  MumpsLu lu("singular");
  try {
    lu.factorise(dense.sparseView());
    FAIL() << "a singular matrix was factorised";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("'singular'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("singular"), std::string::npos) << e.what();
  }
  MumpsLu analysed("pattern");
  analysed.factorise(small_unsymmetric_matrix());
  SparseMatrix other = small_unsymmetric_matrix();
  other.coeffRef(0, 3) = 1.0;  // one entry more: a new pattern needs a new solver
  EXPECT_THROW(analysed.factorise(other), std::invalid_argument);
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

TEST(MumpsLu, OrdersTheGraphOfTheBlocks) {
  // A 27-point stencil of 3 x 3 blocks on a 10^3 grid (the pattern a meshless cloud's node pairs make), its values
  // a diagonally dominant symmetric matrix: with block_size 3 MUMPS orders the 1,000 nodes instead of the 3,000
  // unknowns, and solves the same system.
  const UmfpackMatrix pattern = grid_pattern(10, 3);
  SparseMatrix a(pattern.rows(), pattern.cols());
  std::vector<Eigen::Triplet<double>> entries;
  for (Eigen::Index i = 0; i < pattern.outerSize(); ++i)
    for (UmfpackMatrix::InnerIterator it(pattern, i); it; ++it) {
      const long r = it.row(), c = it.col();
      entries.emplace_back(r, c, r == c ? 60.0 : -1.0 / (1.0 + static_cast<double>((r * 7 + c * 7) % 5)));
    }
  a.setFromTriplets(entries.begin(), entries.end());
  const Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(a.rows(), -1.0, 2.0);
  const Eigen::VectorXd b = a * x;
  MumpsLu unknowns("unknowns' graph"), nodes("node graph", 0.0, false, 3);
  unknowns.factorise(a);
  nodes.factorise(a);
  EXPECT_LT((unknowns.solve(b) - x).norm(), 1e-13 * x.norm());
  EXPECT_LT((nodes.solve(b) - x).norm(), 1e-13 * x.norm());
  std::cout << "10^3 grid of 3 x 3 blocks: " << unknowns.factorisation_flops() / 1e9 << " Gflop ordering the unknowns, "
            << nodes.factorisation_flops() / 1e9 << " Gflop ordering the nodes\n";
  // 0.505 against 0.579 Gflop (0.87x) when this was written; METIS is deterministic.
  EXPECT_LT(nodes.factorisation_flops(), 0.9 * unknowns.factorisation_flops());
  // An order that is no multiple of the block size is refused before MUMPS sees it; so is a block size below 1.
  MumpsLu pairs("pairs", 0.0, false, 2);
  try {
    pairs.factorise(small_unsymmetric_matrix().block(0, 0, 3, 3));
    ADD_FAILURE() << "a 3 x 3 matrix was factorised in blocks of 2";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("the matrix order 3 is not a multiple of the block size 2"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(MumpsLu("none", 0.0, false, 0), std::invalid_argument);
}

TEST(EfgLinearSolvers, EstimateRejectsAnUncompressedMatrix) {
  UmfpackMatrix a(3, 3);
  a.insert(0, 0) = 1.0;  // insert leaves the matrix uncompressed
  EXPECT_THROW(estimate_direct_solver(a), std::invalid_argument);
}

}  // namespace
}  // namespace meshless

int main(int argc, char** argv) {
  // The Krylov solver runs on PETSc and the direct solver on MUMPS, which need MPI and PETSc initialised; only the
  // program name is passed on, so that PETSc does not read GoogleTest's flags.
  int petsc_argc = 1;
  const core::SingletonMpiSessionDirectory session_directory;  // outlives MPI: ctest runs suites side by side
  dealii::Utilities::MPI::MPI_InitFinalize mpi(petsc_argc, argv, 1);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
