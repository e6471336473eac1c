// The EFG model's step cut-back and admissibility check on a bar in uniaxial compression (nu = 0, k = 1),
// where the 1-D law of eq. 10 holds exactly: sigma = factor * K1 * N(eps), so no compressive stress beyond
// factor * K1 / (4k) has an equilibrium (docs/MATERIAL.md §1.5).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <vector>

#include "core/inadmissible_strain.hpp"
#include "core/step_cutback.hpp"
#include "meshless/verification/box_mesh.hpp"
#include "meshless/efg/efg_model.hpp"

namespace meshless {
namespace {

constexpr double kLength = 0.04, kWidth = 0.01;
// 87 % of the instantaneous limit K1/(4k) = 1500 Pa: Newton needs more iterations on longer steps.
constexpr double kPressure = 1300.0;

/// 40 x 10 x 10 mm bar, penalty-clamped at x = 0, uniform traction -pressure e_x on x = L, ramped linearly
/// over 1 s and held, with `steps` equal steps to `total` seconds.
EfgProblem compressed_bar(double pressure, int steps, double total) {
  auto tagger = [](const Eigen::Vector3d& c, const Eigen::Vector3d&) {
    if (c.x() < 1e-12) return core::FaceTag::fixed;
    if (c.x() > kLength - 1e-12) return core::FaceTag::load;
    return core::FaceTag::free_surface;
  };
  EfgProblem p;
  p.name = "compressed bar";
  p.mesh = make_box_mesh(Eigen::Vector3d::Zero(), Eigen::Vector3d(kLength, kWidth, kWidth), 8, 2, 2, tagger);
  p.material = {6000.0, 12000.0, 18000.0, 0.0, 1.0};  // shipped K1, K2, eta; nu = 0 keeps it uniaxial
  p.support.d_max = 2.0;
  p.support.k = 6;
  p.quadrature_order = 2;
  p.node_spacing = kWidth / 2;
  p.penalty_factor = 1e3;
  p.traction = [pressure](const Eigen::Vector3d&) { return Eigen::Vector3d(-pressure, 0.0, 0.0); };
  p.load_scale = [](double t) { return std::min(t, 1.0); };
  for (int n = 1; n <= steps; ++n) p.step_times.push_back(total * n / steps);
  return p;
}

TEST(EfgCutback, NoCutbackGivesExactlyPlainStepping) {
  // 600 Pa is 40 % of the instantaneous limit K1/4: every step converges at once.
  EfgProblem plain = compressed_bar(600.0, 4, 2.0), guarded = compressed_bar(600.0, 4, 2.0);
  plain.min_step = 0.0;  // cut-back disabled
  guarded.min_step = 0.5 / 64;
  EfgModel a(std::move(plain)), b(std::move(guarded));
  a.run();
  b.run();
  for (const StepRecord& s : b.steps()) {
    EXPECT_EQ(s.substeps, 1);
    EXPECT_EQ(s.cutbacks, 0);
  }
  EXPECT_EQ(a.nodal_parameters(), b.nodal_parameters());  // bitwise
  const double strain = b.displacement_at(Eigen::Vector3d(kLength, kWidth / 2, kWidth / 2)).x() / kLength;
  EXPECT_LT(strain, -0.05);
  EXPECT_GT(b.smallest_margin().margin, 0.0);
  EXPECT_LT(b.smallest_margin().margin, 1.0 + 2.0 * strain + 0.05);  // about 1 + 2 k eps
}

/// Newton iterations of each step of a plain run (no cut-back, no iteration limit that matters).
std::vector<int> iterations_per_step(int steps, const EfgOptions& options) {
  EfgOptions unlimited = options;
  unlimited.max_newton_iterations = 100;
  EfgModel model(compressed_bar(kPressure, steps, 1.0), unlimited);
  model.run();
  std::vector<int> n;
  for (const StepRecord& s : model.steps()) n.push_back(s.newton_iterations);
  return n;
}

/// Full Newton (a fresh tangent every iteration) and an iteration limit at which one 1 s step of the ramp
/// fails while two 0.5 s steps converge, measured rather than assumed.
EfgOptions options_where_only_half_steps_converge() {
  static const EfgOptions measured = [] {
    EfgOptions options;
    options.refactor_contraction = 0.0;
    options.earlier_factors_max_iterations = 0;  // every tangent factorised, none solved by GMRES
    const std::vector<int> one = iterations_per_step(1, options), two = iterations_per_step(2, options);
    options.max_newton_iterations = *std::max_element(two.begin(), two.end());
    std::cout << "Newton iterations: one 1 s step " << one[0] << ", two 0.5 s steps " << two[0] << " and "
              << two[1] << "; limit set to " << options.max_newton_iterations << "\n";
    EXPECT_GT(one[0], options.max_newton_iterations) << "the bar no longer needs a cut-back: raise kPressure";
    return options;
  }();
  return measured;
}

TEST(EfgCutback, HalvedStepEqualsPlainHalfStepsAtTheRequestedTimes) {
  const EfgOptions options = options_where_only_half_steps_converge();
  EfgProblem coarse = compressed_bar(kPressure, 1, 1.0), fine = compressed_bar(kPressure, 2, 1.0);
  coarse.min_step = 0.5;
  fine.min_step = 0.0;
  EfgModel cut(std::move(coarse), options), plain(std::move(fine), options);
  cut.run();
  plain.run();
  ASSERT_EQ(cut.steps().size(), 1u);
  const StepRecord& s = cut.steps()[0];
  EXPECT_EQ(s.cutbacks, 1);
  EXPECT_EQ(s.substeps, 2);
  EXPECT_DOUBLE_EQ(s.time, 1.0);
  ASSERT_EQ(s.failed_attempts.size(), 1u);
  EXPECT_EQ(s.failed_attempts[0].t_end, 1.0);
  EXPECT_EQ(s.failed_attempts[0].iterations, options.max_newton_iterations);
  EXPECT_NE(s.failed_attempts[0].failure.find("max_newton_iterations"), std::string::npos);
  // The failed attempt leaves no trace: the sub-steps are exactly the plain half steps.
  EXPECT_EQ(cut.nodal_parameters(), plain.nodal_parameters());  // bitwise
  EXPECT_EQ(cut.smallest_margin().margin, plain.smallest_margin().margin);
}

TEST(EfgCutback, StepThatFailsAtTheMinimumListsEveryAttempt) {
  const EfgOptions options = options_where_only_half_steps_converge();
  EfgProblem p = compressed_bar(kPressure, 1, 1.0);
  p.min_step = 1.0;  // no halving allowed
  EfgModel model(std::move(p), options);
  model.setup_system();
  const Eigen::VectorXd before = model.nodal_parameters();
  try {
    model.solve_step(1);
    FAIL() << "expected StepCutBackFailed";
  } catch (const core::StepCutBackFailed& e) {
    std::cout << e.what() << "\n";
    ASSERT_EQ(e.attempts().size(), 1u);
    EXPECT_EQ(e.attempts()[0].iterations, options.max_newton_iterations);
    EXPECT_GT(e.attempts()[0].residuals.back(), options.newton_tolerance);
    EXPECT_NE(std::string(e.what()).find("compressed bar"), std::string::npos);
    EXPECT_EQ(model.nodal_parameters(), before);  // the committed state is restored
  }
}

TEST(EfgCutback, CompressionBeyondTheLawsLimitStopsWithTheAdmissibilityError) {
  // Instantaneous step (dt = 0, factor 1): 2000 Pa exceeds the largest compressive stress K1/(4k) = 1500 Pa.
  EfgProblem p = compressed_bar(2000.0, 1, 1.0);
  p.step_times = {0.0};
  p.load_scale = [](double) { return 1.0; };
  p.min_step = 0.01;
  EfgModel model(std::move(p));
  model.setup_system();
  try {
    model.solve_step(1);
    FAIL() << "expected InadmissibleStrain";
  } catch (const core::InadmissibleStrain& e) {
    std::cout << e.what() << "\n";
    EXPECT_LE(e.margin(), 0.0);
    EXPECT_LE(e.principal_strain(), -0.5);
    EXPECT_DOUBLE_EQ(e.limit_strain(), -0.5);
    EXPECT_EQ(e.time(), 0.0);
    EXPECT_TRUE((e.point().array() >= -1e-12).all() && e.point().x() <= kLength && e.point().y() <= kWidth);
    EXPECT_NE(std::string(e.what()).find("meshless (EFG) model 'compressed bar'"), std::string::npos);
  }
}

TEST(EfgCutback, SlopeFloorCarriesTheCompressionPastTheLimitAlongTheClosedForm) {
  // The same 2000 Pa at once, with /material/slope_floor = 0.2 (docs/MATERIAL.md §1.7): K1 n(eps) = -2000 Pa,
  // n(eps) = -1/3 lies past n(lambda_c) = -0.24 (lambda_c = -0.4), so eps = -0.4 + (-1/3 + 0.24)/0.2 = -13/15.
  // The MLS functions reproduce the uniform state and the penalty only shifts it, so the bar's strain between
  // its ends is exact to the Newton tolerance.
  EfgProblem p = compressed_bar(2000.0, 1, 1.0);
  p.step_times = {0.0};
  p.load_scale = [](double) { return 1.0; };
  p.min_step = 0.01;
  p.material.slope_floor = 0.2;
  EfgModel model(std::move(p));
  model.run();
  const Eigen::Vector3d mid(0.0, kWidth / 2, kWidth / 2);
  const double strain =
      (model.displacement_at(mid + Eigen::Vector3d(kLength, 0, 0)).x() - model.displacement_at(mid).x()) / kLength;
  std::cout << "strain " << strain << ", smallest margin " << model.steps().back().admissibility_margin << "\n";
  EXPECT_NEAR(strain, -13.0 / 15.0, 1e-7);
  EXPECT_NEAR(model.steps().back().admissibility_margin, 1.0 + 2.0 * strain, 1e-6);
}

}  // namespace
}  // namespace meshless
