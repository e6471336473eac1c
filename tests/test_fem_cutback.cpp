// The FEM reference's step cut-back and admissibility check on a bar in uniaxial compression (nu = 0, k = 1),
// where the 1-D law of eq. 10 holds exactly: sigma = factor * K1 * N(eps), so no compressive stress beyond
// factor * K1 / (4k) has an equilibrium (docs/MATERIAL.md §1.5). The same bar as tests/test_efg_cutback.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <vector>

#include "core/inadmissible_strain.hpp"
#include "core/step_cutback.hpp"
#include "experiments/models/model_result.hpp"
#include "meshless/verification/box_mesh.hpp"
#include "reference_fem/fem_model.hpp"

namespace reference_fem {
namespace {

constexpr double kLength = 0.04, kWidth = 0.01;
// 87 % of the instantaneous limit K1/(4k) = 1500 Pa: Newton needs more iterations on longer steps.
constexpr double kPressure = 1300.0;

core::TetMesh bar_mesh() {
  auto tagger = [](const Eigen::Vector3d& c, const Eigen::Vector3d&) {
    if (c.x() < 1e-12) return core::FaceTag::fixed;
    if (c.x() > kLength - 1e-12) return core::FaceTag::load;
    return core::FaceTag::free_surface;
  };
  return meshless::make_box_mesh(Eigen::Vector3d::Zero(), Eigen::Vector3d(kLength, kWidth, kWidth), 4, 1, 1, tagger);
}

SolverParameters bar_parameters(int max_iterations, double min_step) {
  SolverParameters p;
  p.material = {6000.0, 12000.0, 18000.0, 0.0, 1.0};  // shipped K1, K2, eta; nu = 0 keeps it uniaxial
  p.degree = 1;
  p.newton.max_iterations = max_iterations;
  p.newton.min_step = min_step;
  return p;
}

/// Clamped at x = 0 (with nu = 0 the clamp does not constrain the uniaxial state), traction -pressure e_x on
/// x = L ramped linearly over 1 s and held (or applied at once when `ramp` is false).
BoundaryConditions compression(double pressure, bool ramp) {
  BoundaryConditions bc;
  bc.dirichlet.push_back(DirichletCondition{});
  TractionCondition push;
  push.traction = Eigen::Vector3d(-pressure, 0.0, 0.0);
  if (ramp) push.scale = [](double t) { return std::min(t, 1.0); };
  bc.tractions.push_back(push);
  return bc;
}

const Eigen::MatrixXd kTip = (Eigen::MatrixXd(1, 3) << kLength, kWidth / 2, kWidth / 2).finished();

FemRunResult run(double pressure, const std::vector<double>& times, int max_iterations, double min_step,
                 bool ramp = true) {
  return solve_on_mesh(bar_mesh(), bar_parameters(max_iterations, min_step), compression(pressure, ramp), times,
                       kTip);
}

/// An iteration limit at which one 1 s step of the ramp fails while two 0.5 s steps converge, measured.
int limit_where_only_half_steps_converge() {
  static const int limit = [] {
    const FemRunResult one = run(kPressure, {1.0}, 100, 0.0), two = run(kPressure, {0.5, 1.0}, 100, 0.0);
    const int n1 = one.steps[0].newton_iterations;
    const int n2 = std::max(two.steps[0].newton_iterations, two.steps[1].newton_iterations);
    std::cout << "Newton iterations: one 1 s step " << n1 << ", two 0.5 s steps " << two.steps[0].newton_iterations
              << " and " << two.steps[1].newton_iterations << "\n";
    EXPECT_GT(n1, n2) << "the bar no longer needs a cut-back: raise kPressure";
    return n2;
  }();
  return limit;
}

TEST(FemCutback, NoCutbackGivesExactlyPlainStepping) {
  // 600 Pa is 40 % of the instantaneous limit: every step converges at once.
  const std::vector<double> times = {0.5, 1.0, 1.5, 2.0};
  const FemRunResult plain = run(600.0, times, 25, 0.0), guarded = run(600.0, times, 25, 0.5 / 64);
  for (const StepReport& s : guarded.steps) {
    EXPECT_EQ(s.substeps, 1);
    EXPECT_TRUE(s.failed_attempts.empty());
  }
  EXPECT_EQ(plain.vertex_displacements, guarded.vertex_displacements);  // bitwise
  const double strain = guarded.sample_displacements(0, 0) / kLength;
  std::cout << "tip strain " << strain << ", smallest margin " << guarded.smallest_margin.margin << "\n";
  EXPECT_LT(strain, -0.05);
  // uniaxial: the margin is 1 + 2 k eps_xx, the same at every point
  EXPECT_NEAR(guarded.smallest_margin.margin, 1.0 + 2.0 * strain, 1e-6);
  EXPECT_DOUBLE_EQ(guarded.smallest_margin.time, 2.0);  // creep: the strain grows while the load is held
}

TEST(FemCutback, ExtrapolatedStartChangesThePathNotTheAnswer) {
  // NewtonParameters::extrapolate_start over a ramp and a hold (k = 1, 67 % of the limit): the same creep to
  // Newton's tolerance, in fewer iterations. The predictor skips step 5, the first of the hold, where the load's
  // rate changes (core/step_predictor.hpp).
  const std::vector<double> times = {0.2, 0.4, 0.6, 0.8, 1.0, 1.2, 1.4, 1.6, 1.8, 2.0};
  auto solve = [&](bool extrapolate) {
    SolverParameters p = bar_parameters(25, 0.0);
    p.newton.extrapolate_start = extrapolate;
    return solve_on_mesh(bar_mesh(), p, compression(1000.0, true), times, kTip);
  };
  const FemRunResult plain = solve(false), predicted = solve(true);
  auto iterations = [](const FemRunResult& f) {
    int n = 0;
    for (const StepReport& s : f.steps) n += s.newton_iterations;
    return n;
  };
  const double tip = plain.sample_displacements(0, 0);
  const double difference = std::abs(predicted.sample_displacements(0, 0) - tip) / std::abs(tip);
  std::cout << "Newton iterations: plain " << iterations(plain) << ", extrapolated " << iterations(predicted)
            << "; tip strain " << tip / kLength << ", relative difference " << difference << "\n";
  EXPECT_LT(difference, 1e-9);  // measured 1.9e-10
  EXPECT_LE(iterations(predicted), iterations(plain) - 5);  // measured 26 against 31
  for (const StepReport& s : predicted.steps) EXPECT_TRUE(s.retried_plain.empty());
  EXPECT_EQ(predicted.steps[0].newton_iterations, plain.steps[0].newton_iterations);  // nothing to extrapolate
  EXPECT_EQ(predicted.steps[5].newton_iterations, plain.steps[5].newton_iterations);  // the hold's first step
}

TEST(FemCutback, ConvergenceConfirmedWithoutTheTangentGivesTheSameAnswer) {
  // NewtonParameters::confirm_without_tangent over a ramp and a hold (k = 1): the last assembly of each step is the
  // residual alone, and the run is the same to the bit, with one tangent fewer per step.
  const std::vector<double> times = {0.2, 0.4, 0.6, 0.8, 1.0, 1.2, 1.4, 1.6, 1.8, 2.0};
  auto solve = [&](bool confirm_without_tangent) {
    SolverParameters p = bar_parameters(25, 0.0);
    p.newton.confirm_without_tangent = confirm_without_tangent;
    return solve_on_mesh(bar_mesh(), p, compression(1000.0, true), times, kTip);
  };
  const FemRunResult full = solve(false), confirmed = solve(true);
  EXPECT_EQ(full.vertex_displacements, confirmed.vertex_displacements);  // bitwise
  ASSERT_EQ(full.steps.size(), confirmed.steps.size());
  for (std::size_t i = 0; i < full.steps.size(); ++i) {
    const StepReport &a = full.steps[i], &b = confirmed.steps[i];
    EXPECT_EQ(a.residuals, b.residuals) << "step " << a.step;
    EXPECT_EQ(a.residual_only_assemblies, 0);
    EXPECT_EQ(a.tangent_assemblies, a.newton_iterations + 1);
    EXPECT_EQ(b.residual_only_assemblies, 1) << "step " << b.step;  // the confirmation, predicted at every step
    EXPECT_EQ(b.tangent_assemblies, b.newton_iterations) << "step " << b.step;
  }
}

TEST(FemCutback, HalvedStepEqualsPlainHalfStepsAtTheRequestedTimes) {
  const int limit = limit_where_only_half_steps_converge();
  const FemRunResult cut = run(kPressure, {1.0}, limit, 0.5), plain = run(kPressure, {0.5, 1.0}, limit, 0.0);
  ASSERT_EQ(cut.steps.size(), 1u);
  const StepReport& s = cut.steps[0];
  EXPECT_EQ(s.substeps, 2);
  EXPECT_DOUBLE_EQ(s.time, 1.0);
  ASSERT_EQ(s.failed_attempts.size(), 1u);
  EXPECT_EQ(s.failed_attempts[0].t_start, 0.0);
  EXPECT_EQ(s.failed_attempts[0].t_end, 1.0);
  EXPECT_NE(s.failed_attempts[0].failure.find("max_newton_iterations"), std::string::npos);
  EXPECT_GT(s.failed_attempts[0].residuals.back(), 1e-8);
  // The failed attempt leaves no trace: the sub-steps are the plain half steps.
  EXPECT_EQ(cut.vertex_displacements, plain.vertex_displacements);  // bitwise
  EXPECT_EQ(cut.smallest_margin.margin, plain.smallest_margin.margin);
}

TEST(FemCutback, TimingsJsonRecordsTheCutBackAndTheSmallestMargin) {
  // A cut-back step followed by a plain one, through timings_json (the per-step fields as `tissue solve fem`
  // fills them in experiments/commands/solve_commands.cpp).
  const int limit = limit_where_only_half_steps_converge();
  const FemRunResult f = run(kPressure, {1.0, 1.05}, limit, 0.5);  // held longer, it creeps past the limit
  experiments::ModelResult r;
  r.model = "fem";
  for (const StepReport& s : f.steps)
    r.steps.push_back({s.step, s.time, s.wall_seconds, s.assembly_seconds, s.solve_seconds, s.newton_iterations,
                       s.residuals, s.linear_iterations, s.substeps, s.failed_attempts, s.admissibility_margin});
  r.steps[1].rejected_mixes = 2;  // a meshless model's field (the FEM does not mix), written per step
  const nlohmann::json j = experiments::timings_json(r);
  EXPECT_EQ(j["steps"][0]["rejected_mixes"], 0);
  EXPECT_EQ(j["steps"][1]["rejected_mixes"], 2);
  EXPECT_EQ(j["cutbacks_total"], 1);
  ASSERT_EQ(j["steps"].size(), 2u);
  const nlohmann::json& first = j["steps"][0];
  EXPECT_EQ(first["substeps"], 2);
  EXPECT_EQ(first["cutbacks"], 1);
  ASSERT_EQ(first["failed_attempts"].size(), 1u);
  EXPECT_EQ(first["failed_attempts"][0]["t_start"], 0.0);
  EXPECT_EQ(first["failed_attempts"][0]["t_end"], 1.0);
  EXPECT_EQ(first["failed_attempts"][0]["newton_iterations"], limit);
  EXPECT_EQ(first["failed_attempts"][0]["relative_residuals"].size(), static_cast<std::size_t>(limit) + 1);
  EXPECT_EQ(j["steps"][1]["cutbacks"], 0);
  EXPECT_EQ(j["steps"][1]["substeps"], 1);
  // The run's smallest margin is that of the solver (over the converged states), here at the last step, and it
  // is 1 + 2k eps of the uniaxial strain.
  const double strain = f.sample_displacements(0, 0) / kLength;
  std::cout << "timings.json: min_one_plus_2k_lambda " << j["min_one_plus_2k_lambda"] << ", strain " << strain << "\n";
  EXPECT_DOUBLE_EQ(j["min_one_plus_2k_lambda"].get<double>(), f.smallest_margin.margin);
  EXPECT_DOUBLE_EQ(f.smallest_margin.time, 1.05);
  EXPECT_NEAR(j["min_one_plus_2k_lambda"].get<double>(), 1.0 + 2.0 * strain, 1e-6);
}

TEST(FemCutback, StepThatFailsAtTheMinimumListsEveryAttempt) {
  const int limit = limit_where_only_half_steps_converge();
  try {
    run(kPressure, {1.0}, limit, 1.0);  // no halving allowed
    FAIL() << "expected StepCutBackFailed";
  } catch (const core::StepCutBackFailed& e) {
    std::cout << e.what() << "\n";
    ASSERT_EQ(e.attempts().size(), 1u);
    EXPECT_EQ(e.attempts()[0].iterations, limit);
    EXPECT_NE(std::string(e.what()).find("FEM reference"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("/time/min_step"), std::string::npos);
  }
}

TEST(FemCutback, CompressionBeyondTheLawsLimitStopsWithTheAdmissibilityError) {
  // Instantaneous step (dt = 0, factor 1): 2000 Pa exceeds the largest compressive stress K1/(4k) = 1500 Pa.
  try {
    run(2000.0, {0.0}, 25, 0.01, /*ramp=*/false);
    FAIL() << "expected InadmissibleStrain";
  } catch (const core::InadmissibleStrain& e) {
    std::cout << e.what() << "\n";
    EXPECT_LE(e.margin(), 0.0);
    EXPECT_LE(e.principal_strain(), -0.5);
    EXPECT_DOUBLE_EQ(e.limit_strain(), -0.5);
    EXPECT_EQ(e.time(), 0.0);
    EXPECT_TRUE((e.point().array() >= 0.0).all() && e.point().x() <= kLength && e.point().y() <= kWidth &&
                e.point().z() <= kWidth);
    EXPECT_NE(std::string(e.what()).find("FEM reference"), std::string::npos);
  }
}

TEST(FemCutback, SlopeFloorCarriesTheCompressionPastTheLimitAlongTheClosedForm) {
  // The same 2000 Pa at once, with /material/slope_floor = 0.2 (docs/MATERIAL.md §1.7): K1 n(eps) = -2000 Pa,
  // n(eps) = -1/3 lies past n(lambda_c) = -0.24 (lambda_c = -0.4), so eps = -0.4 + (-1/3 + 0.24)/0.2 = -13/15.
  // P1 reproduces the uniform uniaxial state, so the tip moves by eps L to the Newton tolerance.
  SolverParameters p = bar_parameters(25, 0.01);
  p.material.slope_floor = 0.2;
  BoundaryConditions bc = compression(2000.0, /*ramp=*/false);
  const FemRunResult r = solve_on_mesh(bar_mesh(), p, bc, {0.0}, kTip);
  const double strain = r.sample_displacements(0, 0) / kLength;
  std::cout << "strain " << strain << " after " << r.steps[0].newton_iterations << " Newton iterations, margin "
            << r.smallest_margin.margin << "\n";
  EXPECT_NEAR(strain, -13.0 / 15.0, 1e-8);
  EXPECT_NEAR(r.smallest_margin.margin, 1.0 + 2.0 * strain, 1e-7);  // the paper's margin, past its limit
  EXPECT_LE(r.steps[0].newton_iterations, 8);
}

}  // namespace
}  // namespace reference_fem
