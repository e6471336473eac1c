// Tests of the nonlinear Kelvin law (paper §2, eqs. 9–13; core/kelvin_law.hpp, docs/MATERIAL.md).
//
// Every test checks numbers against an independent answer: closed-form relaxation/creep of the standard
// linear solid, a direct quadrature of eq. 10, finite differences of update(), Hooke's law and rotation.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <functional>
#include <iostream>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/inadmissible_strain.hpp"
#include "core/convergence_rate.hpp"
#include "core/kelvin_law.hpp"

namespace core {
namespace {

// Soft-tissue-like constants; tau = eta/(K1+K2) = 0.2 s, creep time eta/K2 = 0.6 s.
KelvinParameters make_parameters(double nu, double k) {
  KelvinParameters p;
  p.K1 = 2.0e3;
  p.K2 = 1.0e3;
  p.eta = 600.0;
  p.nu = nu;
  p.k = k;
  return p;
}

Vector6 uniaxial_strain(double eps_xx) {
  Vector6 v = Vector6::Zero();
  v(0) = eps_xx;
  return v;
}

// ---------------------------------------------------------------------------------------------------
// Relaxation: step strain eps0 applied in an instantaneous (dt = 0) step, then held. The recursion is
// exact here because N is constant within every later step.
TEST(KelvinLaw, StepStrainRelaxationIsExact) {
  const KelvinParameters p = make_parameters(/*nu=*/0.0, /*k=*/0.0);
  const KelvinLaw law(p);
  const double tau = p.relaxation_time();
  const double eps0 = 0.05;

  KelvinState state;
  law.update(KelvinState{}, uniaxial_strain(eps0), 0.0, &state);
  EXPECT_NEAR(state.stress(0), p.K1 * eps0, 1e-12 * p.K1 * eps0);  // instantaneous response is K1 eps0

  // Deliberately uneven steps: exactness must not depend on a uniform dt.
  const std::vector<double> steps = {0.01 * tau, 0.37 * tau, 0.05 * tau, 1.3 * tau, 2.0 * tau, 0.5 * tau};
  double t = 0.0;
  for (double dt : steps) {
    KelvinState next;
    law.update(state, uniaxial_strain(eps0), dt, &next);
    state = next;
    t += dt;
    const double exact = eps0 * p.K1 / (p.K1 + p.K2) * (p.K2 + p.K1 * std::exp(-t / tau));
    EXPECT_LT(std::abs(state.stress(0) - exact) / exact, 1e-10) << "t = " << t;
    EXPECT_NEAR(state.stress(0), eps0 * p.relaxation_modulus(t), 1e-10 * exact);
    // nu = 0: the other normal stresses stay zero (uniaxial 1-D reading).
    EXPECT_EQ(state.stress(1), 0.0);
    EXPECT_EQ(state.stress(2), 0.0);
  }
}

// ---------------------------------------------------------------------------------------------------
// Creep: hold sigma_xx = sigma0 (other stresses zero, nu = 0 so xx decouples) and solve for eps_xx each
// step by scalar Newton with the consistent tangent. Returns the max relative error over [0, t_end].
double creep_max_relative_error(const KelvinLaw& law, double sigma0, double dt, double t_end) {
  const KelvinParameters& p = law.parameters();
  const auto exact = [&](double t) {
    return sigma0 / p.K1 + sigma0 / p.K2 * (1.0 - std::exp(-p.K2 * t / p.eta));
  };
  const auto solve_step = [&](const KelvinState& old_state, double step, KelvinState* new_state) {
    double eps = old_state.strain(0);
    for (int it = 0; it < 50; ++it) {
      const KelvinResponse r = law.update(old_state, uniaxial_strain(eps), step);
      const double residual = r.stress(0) - sigma0;
      if (std::abs(residual) < 1e-13 * std::abs(sigma0)) break;
      eps -= residual / r.tangent(0, 0);
    }
    law.update(old_state, uniaxial_strain(eps), step, new_state);
  };

  KelvinState state;
  solve_step(KelvinState{}, 0.0, &state);  // the stress step at t = 0 is instantaneous
  double max_error = std::abs(state.strain(0) - exact(0.0)) / exact(0.0);
  const int n = static_cast<int>(std::lround(t_end / dt));
  for (int i = 1; i <= n; ++i) {
    KelvinState next;
    solve_step(state, dt, &next);
    state = next;
    const double e = exact(i * dt);
    max_error = std::max(max_error, std::abs(state.strain(0) - e) / e);
  }
  return max_error;
}

TEST(KelvinLaw, StepStressCreepConvergesToAnalyticSolution) {
  const KelvinParameters p = make_parameters(/*nu=*/0.0, /*k=*/0.0);
  const KelvinLaw law(p);
  const double tau = p.relaxation_time();
  const double sigma0 = 100.0;
  const double t_end = 5.0 * tau;

  const std::vector<double> divisors = {25.0, 50.0, 100.0, 200.0};
  std::vector<double> errors;
  for (double d : divisors) errors.push_back(creep_max_relative_error(law, sigma0, tau / d, t_end));

  // Observed order: least-squares slope of log(error) against log(dt), plus the pairwise ratios.
  std::vector<double> dt;
  for (double d : divisors) dt.push_back(tau / d);
  const double order = core::convergence_rate(dt, errors);
  for (size_t i = 0; i < divisors.size(); ++i) {
    std::cout << "creep dt = tau/" << divisors[i] << "  max rel error = " << errors[i];
    if (i > 0) std::cout << "  pairwise order = " << std::log2(errors[i - 1] / errors[i]);
    std::cout << "\n";
  }
  std::cout << "creep observed order (LSQ fit) = " << order << "\n";
  ::testing::Test::RecordProperty("creep_observed_order", std::to_string(order));
  ::testing::Test::RecordProperty("creep_error_dt_tau_over_50", std::to_string(errors[1]));

  // Measured: errors 1.03e-5, 2.570e-6, 6.43e-7, 1.61e-7, order 1.99998. The recursion is exact for piecewise-linear
  // strain histories, so it is a second-order collocation scheme; the error itself is plain arithmetic (no solver),
  // so it is asserted to 0.1 %.
  EXPECT_NEAR(errors[1], 2.5702e-6, 2.6e-9) << "dt = tau/50";
  EXPECT_NEAR(order, 2.0, 0.01);
  for (size_t i = 1; i < errors.size(); ++i) EXPECT_LT(errors[i], errors[i - 1]);
}

// ---------------------------------------------------------------------------------------------------
// Independent reference for eq. 10 in 1-D: sigma(t) = int_0^t E(t-s) dN(eps(s))/ds ds, evaluated with
// composite Simpson. Written directly from the integral, without the recursion.
double quadrature_stress(const KelvinParameters& p, const std::function<double(double)>& eps,
                         const std::function<double(double)>& eps_rate, double t_upper_rate, double t,
                         int intervals) {
  // The strain rate is smooth on [0, t_upper_rate] and zero afterwards, so integrate only there.
  const double b = std::min(t, t_upper_rate);
  if (b <= 0.0) return 0.0;
  const auto integrand = [&](double s) {
    const double dn_ds = (1.0 + 2.0 * p.k * eps(s)) * eps_rate(s);  // d/ds (eps + k eps^2)
    return p.relaxation_modulus(t - s) * dn_ds;
  };
  const int n = intervals + (intervals % 2);  // Simpson needs an even count
  const double h = b / n;
  double sum = integrand(0.0) + integrand(b);
  for (int i = 1; i < n; ++i) sum += (i % 2 ? 4.0 : 2.0) * integrand(i * h);
  return sum * h / 3.0;
}

// Runs the recursion for eps(t) = r t up to eps_max (then held) and returns the max relative error
// against the quadrature over the nodes in (0, t_end].
double ramp_max_relative_error(const KelvinLaw& law, double dt, double t_end, double eps_max,
                               double ramp_time) {
  const KelvinParameters& p = law.parameters();
  const double rate = eps_max / ramp_time;
  const auto eps = [&](double s) { return std::min(rate * s, eps_max); };
  const auto eps_rate = [&](double s) { return s <= ramp_time ? rate : 0.0; };

  KelvinState state;
  double max_error = 0.0;
  const int n = static_cast<int>(std::lround(t_end / dt));
  for (int i = 1; i <= n; ++i) {
    const double t = i * dt;
    KelvinState next;
    law.update(state, uniaxial_strain(eps(t)), dt, &next);
    state = next;
    const double reference = quadrature_stress(p, eps, eps_rate, ramp_time, t, 4000);
    max_error = std::max(max_error, std::abs(state.stress(0) - reference) / std::abs(reference));
  }
  return max_error;
}

TEST(KelvinLaw, NonlinearRampMatchesQuadratureOfEq10) {
  const KelvinParameters p = make_parameters(/*nu=*/0.0, /*k=*/2.0);
  const KelvinLaw law(p);
  const double tau = p.relaxation_time();
  const double ramp_time = 2.0 * tau;  // eps reaches 0.2 at 2 tau, then held to 4 tau (relaxation too)
  const double t_end = 4.0 * tau;

  // Sanity of the reference itself: its quadrature error must be far below the tolerances used below.
  {
    const double rate = 0.2 / ramp_time;
    const auto eps = [&](double s) { return std::min(rate * s, 0.2); };
    const auto eps_rate = [&](double s) { return s <= ramp_time ? rate : 0.0; };
    const double coarse = quadrature_stress(p, eps, eps_rate, ramp_time, 3.0 * tau, 4000);
    const double fine = quadrature_stress(p, eps, eps_rate, ramp_time, 3.0 * tau, 16000);
    EXPECT_LT(std::abs(coarse - fine) / std::abs(fine), 1e-12);
  }

  std::vector<double> errors;
  for (double d : {25.0, 50.0, 100.0, 200.0}) {
    errors.push_back(ramp_max_relative_error(law, tau / d, t_end, 0.2, ramp_time));
    std::cout << "ramp k=2 dt = tau/" << d << "  max rel error = " << errors.back() << "\n";
  }
  std::cout << "ramp observed order (tau/100 -> tau/200) = " << std::log2(errors[2] / errors[3]) << "\n";
  ::testing::Test::RecordProperty("ramp_error_dt_tau_over_200", std::to_string(errors.back()));

  // Measured 3.5e-5, 8.8e-6, 2.214e-6, 5.545e-7 (order 1.997): second order, from interpolating the quadratic N(t)
  // linearly. The quadrature reference is exact to 1e-12, so the error is asserted to 0.2 %.
  EXPECT_NEAR(errors.back(), 5.545e-7, 1.1e-9);
  EXPECT_NEAR(std::log2(errors[2] / errors[3]), 1.997, 0.01);
  for (size_t i = 1; i < errors.size(); ++i) EXPECT_LT(errors[i], errors[i - 1]) << "halving dt, i=" << i;
}

// ---------------------------------------------------------------------------------------------------
Vector6 random_strain(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  Vector6 v;
  for (int i = 0; i < 6; ++i) v(i) = u(rng);
  return v;
}

TEST(KelvinLaw, AdjustedStrainJacobianMatchesFiniteDifferences) {
  const KelvinLaw law(make_parameters(/*nu=*/0.3, /*k=*/2.5));
  std::mt19937 rng(7);
  const Vector6 strain = random_strain(rng, 0.1);
  const Matrix6 jacobian = law.adjusted_strain_jacobian(strain);
  const double h = 1e-6;
  Matrix6 fd;
  for (int j = 0; j < 6; ++j) {
    const Vector6 dh = h * Vector6::Unit(j);
    fd.col(j) = (law.adjusted_strain(strain + dh) - law.adjusted_strain(strain - dh)) / (2.0 * h);
  }
  EXPECT_LT((jacobian - fd).norm() / jacobian.norm(), 1e-8) << "analytic\n" << jacobian << "\nfd\n" << fd;
  // Engineering-shear check by hand: N_xy(tensor) = eps_xy + k (eps_xx + eps_yy) eps_xy + k eps_xz eps_zy,
  // so d(2 N_xy)/d(gamma_xy) = 1 + k (eps_xx + eps_yy).
  EXPECT_NEAR(jacobian(3, 3), 1.0 + 2.5 * (strain(0) + strain(1)), 1e-14);
}

TEST(KelvinLaw, StressOnlyUpdateEqualsTheFullUpdateBitForBit) {
  // The residual-only assemblies of modified Newton call updated_stress(); the tangent-carrying ones call
  // update(). Both must write the same stress and history, or the two kinds of iteration would solve
  // different equations.
  const KelvinParameters p = make_parameters(/*nu=*/0.3, /*k=*/2.0);
  const KelvinLaw law(p);
  std::mt19937 rng(7);
  KelvinState full, stress_only;
  for (int i = 0; i < 5; ++i) {
    const Vector6 strain = random_strain(rng, 0.08);
    const double dt = 0.2 * (i + 1) * p.relaxation_time();
    KelvinState next_full, next_stress_only;
    const KelvinResponse r = law.update(full, strain, dt, &next_full);
    const Vector6 s = law.updated_stress(stress_only, strain, dt, &next_stress_only);
    ASSERT_TRUE(s == r.stress) << "step " << i;
    ASSERT_TRUE(next_full.viscous_stress == next_stress_only.viscous_stress) << "step " << i;
    ASSERT_TRUE(next_full.adjusted_strain == next_stress_only.adjusted_strain) << "step " << i;
    ASSERT_GT(next_full.viscous_stress.norm(), 0.0);  // a history that is exercised
    full = next_full, stress_only = next_stress_only;
  }
  EXPECT_THROW(law.updated_stress(full, Vector6::Constant(std::nan("")), 0.1), std::invalid_argument);
}

TEST(KelvinLaw, ConsistentTangentMatchesFiniteDifferenceOfUpdate) {
  const KelvinParameters p = make_parameters(/*nu=*/0.3, /*k=*/2.0);
  const KelvinLaw law(p);
  const double tau = p.relaxation_time();
  std::mt19937 rng(2020);

  // Build a non-trivial history first so h_n != 0.
  KelvinState state;
  for (int i = 0; i < 3; ++i) {
    KelvinState next;
    law.update(state, random_strain(rng, 0.08), 0.4 * tau, &next);
    state = next;
  }
  const Vector6 strain_new = random_strain(rng, 0.08);
  const double dt = 0.3 * tau;
  const KelvinResponse response = law.update(state, strain_new, dt);

  const double h = 1e-6;
  Matrix6 fd;
  for (int j = 0; j < 6; ++j) {
    const Vector6 dh = h * Vector6::Unit(j);
    fd.col(j) =
        (law.update(state, strain_new + dh, dt).stress - law.update(state, strain_new - dh, dt).stress) /
        (2.0 * h);
  }
  const double rel = (response.tangent - fd).norm() / response.tangent.norm();
  EXPECT_LT(rel, 1e-6) << "analytic\n" << response.tangent << "\nfd\n" << fd;
  EXPECT_LT((response.tangent - fd).cwiseAbs().maxCoeff() / response.tangent.cwiseAbs().maxCoeff(), 1e-6);
  // With k != 0 the tangent is genuinely non-symmetric (documented in the header).
  EXPECT_GT((response.tangent - response.tangent.transpose()).norm(), 1e-6 * response.tangent.norm());

  // eq. 13: Delta sigma = E_k-part + sigma_0 with sigma_0 = (exp(-dt/tau) - 1) h_n.
  const double factor = law.step_modulus_factor(dt);
  const Matrix6 c0 = law.elastic_matrix(p.K1);
  const Vector6 delta_n = law.adjusted_strain(strain_new) - law.adjusted_strain(state.strain);
  const Vector6 sigma0 = (std::exp(-dt / tau) - 1.0) * state.viscous_stress;
  const Vector6 predicted = state.stress + factor * (c0 * delta_n) + sigma0;
  EXPECT_LT((response.stress - predicted).norm() / response.stress.norm(), 1e-12);
}

TEST(KelvinLaw, StepModulusFactorLimits) {
  const KelvinParameters p = make_parameters(0.0, 0.0);
  const KelvinLaw law(p);
  const double g_inf = p.equilibrium_modulus() / p.K1;
  const double tau = p.relaxation_time();
  EXPECT_DOUBLE_EQ(law.step_modulus_factor(0.0), 1.0);
  EXPECT_NEAR(law.step_modulus_factor(1e-14 * tau), 1.0, 1e-13);  // no cancellation for tiny dt
  EXPECT_NEAR(law.step_modulus_factor(1e6 * tau), g_inf, 1e-6);
  const double a = 0.7;
  EXPECT_NEAR(law.step_modulus_factor(a * tau), g_inf + (1.0 - g_inf) * (1.0 - std::exp(-a)) / a, 1e-15);
}

// ---------------------------------------------------------------------------------------------------
TEST(KelvinLaw, ElasticMatrixIsHookesLaw) {
  const double nu = 0.3, young = 5.0e3, s = 120.0;
  const KelvinLaw law(make_parameters(nu, 0.0));
  const Matrix6 c = law.elastic_matrix(young);
  const Matrix6 compliance = c.inverse();

  Vector6 uniaxial = Vector6::Zero();
  uniaxial(0) = s;
  const Vector6 e = compliance * uniaxial;
  EXPECT_NEAR(e(0), s / young, 1e-15);
  EXPECT_NEAR(e(1), -nu * s / young, 1e-15);
  EXPECT_NEAR(e(2), -nu * s / young, 1e-15);
  EXPECT_NEAR(e.tail<3>().norm(), 0.0, 1e-15);

  // Pure shear: engineering gamma_xy = tau_xy / G with G = E / (2 (1 + nu)).
  Vector6 shear = Vector6::Zero();
  shear(3) = s;
  const Vector6 g = compliance * shear;
  EXPECT_NEAR(g(3), s * 2.0 * (1.0 + nu) / young, 1e-15);
  EXPECT_NEAR(g.head<3>().norm(), 0.0, 1e-15);
  EXPECT_LT((c - c.transpose()).norm(), 1e-12 * c.norm());
}

TEST(KelvinLaw, FrameIndifference) {
  const KelvinParameters p = make_parameters(/*nu=*/0.3, /*k=*/2.0);
  const KelvinLaw law(p);
  std::mt19937 rng(11);
  const Vector6 strain = random_strain(rng, 0.1);
  const Matrix3 rotation =
      Eigen::AngleAxisd(0.83, Eigen::Vector3d(0.3, -1.2, 0.7).normalized()).toRotationMatrix();
  const Matrix3 e = voigt_to_strain(strain);
  const Vector6 rotated_strain = strain_to_voigt(rotation * e * rotation.transpose());

  const Matrix3 n = voigt_to_strain(law.adjusted_strain(strain));
  const Matrix3 n_rot = voigt_to_strain(law.adjusted_strain(rotated_strain));
  EXPECT_LT((n_rot - rotation * n * rotation.transpose()).norm(), 1e-14);

  for (double dt : {0.0, 0.5 * p.relaxation_time()}) {
    const Matrix3 s = voigt_to_stress(law.update(KelvinState{}, strain, dt).stress);
    const Matrix3 s_rot = voigt_to_stress(law.update(KelvinState{}, rotated_strain, dt).stress);
    EXPECT_LT((s_rot - rotation * s * rotation.transpose()).norm(), 1e-12 * s.norm()) << "dt = " << dt;
  }
}

TEST(KelvinLaw, StateIsWrittenConsistently) {
  const KelvinParameters p = make_parameters(0.25, 1.5);
  const KelvinLaw law(p);
  std::mt19937 rng(3);
  const Vector6 strain = random_strain(rng, 0.05);
  KelvinState next;
  const KelvinResponse r = law.update(KelvinState{}, strain, 0.1, &next);
  EXPECT_EQ(next.strain, strain);
  EXPECT_EQ(next.adjusted_strain, law.adjusted_strain(strain));
  EXPECT_EQ(next.stress, r.stress);
  // sigma = g_inf C0 N + h (the split of eq. 10).
  const double g_inf = p.equilibrium_modulus() / p.K1;
  const Vector6 split = g_inf * (law.elastic_matrix(p.K1) * next.adjusted_strain) + next.viscous_stress;
  EXPECT_LT((split - r.stress).norm(), 1e-12 * r.stress.norm());
}

// ---------------------------------------------------------------------------------------------------
TEST(KelvinLaw, BadParametersThrow) {
  const auto with = [](auto mutate) {
    KelvinParameters p = make_parameters(0.3, 1.0);
    mutate(p);
    return p;
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(KelvinLaw(with([](KelvinParameters& p) { p.K1 = 0.0; })), std::invalid_argument);
  EXPECT_THROW(KelvinLaw(with([](KelvinParameters& p) { p.K1 = -1.0; })), std::invalid_argument);
  EXPECT_THROW(KelvinLaw(with([](KelvinParameters& p) { p.K2 = 0.0; })), std::invalid_argument);
  EXPECT_THROW(KelvinLaw(with([](KelvinParameters& p) { p.eta = -2.0; })), std::invalid_argument);
  EXPECT_THROW(KelvinLaw(with([](KelvinParameters& p) { p.nu = 0.5; })), std::invalid_argument);
  EXPECT_THROW(KelvinLaw(with([](KelvinParameters& p) { p.nu = 0.7; })), std::invalid_argument);
  EXPECT_THROW(KelvinLaw(with([](KelvinParameters& p) { p.nu = -1.0; })), std::invalid_argument);
  EXPECT_THROW(KelvinLaw(with([nan](KelvinParameters& p) { p.K1 = nan; })), std::invalid_argument);
  EXPECT_THROW(KelvinLaw(with([nan](KelvinParameters& p) { p.k = nan; })), std::invalid_argument);
  EXPECT_NO_THROW(KelvinLaw(with([](KelvinParameters& p) { p.nu = 0.499; })));

  // The message names the offending parameter.
  try {
    KelvinLaw law(with([](KelvinParameters& p) { p.K1 = -1.0; }));
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("K1"), std::string::npos) << e.what();
  }
  try {
    KelvinLaw law(with([](KelvinParameters& p) { p.nu = 0.5; }));
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("nu"), std::string::npos) << e.what();
  }
}

TEST(KelvinLaw, BadUpdateInputsThrowInsteadOfProducingNaN) {
  const KelvinLaw law(make_parameters(0.3, 1.0));
  const Vector6 strain = uniaxial_strain(0.01);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_THROW(law.update(KelvinState{}, strain, -1e-3), std::invalid_argument);
  EXPECT_THROW(law.update(KelvinState{}, strain, nan), std::invalid_argument);
  EXPECT_THROW(law.update(KelvinState{}, strain, inf), std::invalid_argument);
  Vector6 bad = strain;
  bad(4) = nan;
  EXPECT_THROW(law.update(KelvinState{}, bad, 0.1), std::invalid_argument);
  bad(4) = inf;
  EXPECT_THROW(law.update(KelvinState{}, bad, 0.1), std::invalid_argument);
  KelvinState corrupt;
  corrupt.viscous_stress(2) = nan;
  EXPECT_THROW(law.update(corrupt, strain, 0.1), std::invalid_argument);
  EXPECT_NO_THROW(law.update(KelvinState{}, strain, 0.0));
}

// The admissible range (docs/MATERIAL.md §1.5): the margin is the smallest eigenvalue of dN/deps, whose
// eigenvalues are 1 + k (lambda_i + lambda_j) in the principal frame.
TEST(KelvinLaw, AdmissibilityMarginIsTheSmallestEigenvalueOfTheAdjustmentJacobian) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.4, 0.4);
  for (double k : {2.0, 0.7, -1.5}) {
    const KelvinLaw law(make_parameters(0.3, k));
    for (int trial = 0; trial < 50; ++trial) {
      Vector6 e;
      for (int i = 0; i < 6; ++i) e(i) = u(rng);
      const Eigen::VectorXcd ev = Eigen::EigenSolver<Matrix6>(law.adjusted_strain_jacobian(e)).eigenvalues();
      EXPECT_LT(ev.imag().cwiseAbs().maxCoeff(), 1e-10);
      EXPECT_NEAR(law.admissibility_margin(e), ev.real().minCoeff(), 1e-10) << "k = " << k;
      // and the pairwise form 1 + k (lambda_i + lambda_j) gives all six eigenvalues
      const Eigen::Vector3d lambda = KelvinLaw::principal_strains(e);
      const Eigen::VectorXd real = ev.real();
      std::vector<double> expected, actual(real.data(), real.data() + 6);
      for (int i = 0; i < 3; ++i)
        for (int j = i; j < 3; ++j) expected.push_back(1.0 + k * (lambda(i) + lambda(j)));
      std::sort(expected.begin(), expected.end());
      std::sort(actual.begin(), actual.end());
      for (int i = 0; i < 6; ++i) EXPECT_NEAR(actual[i], expected[i], 1e-10);
    }
  }
}

TEST(KelvinLaw, AdmissibleRangeMatchesThePaperOneDimensionalForm) {
  // nu = 0 and uniaxial strain reduce the 3-D law to eq. 10: sigma = K1 N(eps) at dt = 0, so the 1-D tangent
  // is K1 dN/deps = K1 (1 + 2 k eps), which is the margin, and it vanishes where N = eps + k eps^2 peaks.
  const double k = 1.0;
  const KelvinLaw law(make_parameters(0.0, k));
  EXPECT_DOUBLE_EQ(law.limit_strain(), -0.5);
  for (double eps : {-0.6, -0.5, -0.3, 0.0, 0.2}) {
    const KelvinResponse r = law.update(KelvinState{}, uniaxial_strain(eps), 0.0);
    EXPECT_NEAR(r.tangent(0, 0) / 2.0e3, 1.0 + 2.0 * k * eps, 1e-14) << eps;
    EXPECT_NEAR(law.admissibility_margin(uniaxial_strain(eps)), std::min(1.0, 1.0 + 2.0 * k * eps), 1e-14);
  }
  // The smallest stress the material can carry is K1 N(-1/(2k)) = -K1/(4k): no equilibrium below it.
  const double floor = law.update(KelvinState{}, uniaxial_strain(-0.5), 0.0).stress(0);
  EXPECT_NEAR(floor, -2.0e3 / 4.0, 1e-9);
  for (double eps : {-0.45, -0.55, -0.8})
    EXPECT_GT(law.update(KelvinState{}, uniaxial_strain(eps), 0.0).stress(0), floor);
  // k < 0 moves the limit to tension; k = 0 has none.
  EXPECT_DOUBLE_EQ(KelvinLaw(make_parameters(0.3, -2.0)).limit_strain(), 0.25);
  EXPECT_LT(KelvinLaw(make_parameters(0.3, -2.0)).admissibility_margin(uniaxial_strain(0.3)), 0.0);
  EXPECT_TRUE(std::isinf(KelvinLaw(make_parameters(0.3, 0.0)).limit_strain()));
  EXPECT_EQ(KelvinLaw(make_parameters(0.3, 0.0)).admissibility_margin(uniaxial_strain(-5.0)), 1.0);
}

// ---------------------------------------------------------------------------------------------------
// The slope floor (docs/MATERIAL.md §1.7): past the principal strain where the slope 1 + 2k lambda of N falls to
// delta, N continues along its tangent line there, with slope delta.

KelvinParameters with_floor(double nu, double k, double delta) {
  KelvinParameters p = make_parameters(nu, k);
  p.slope_floor = delta;
  return p;
}

TEST(KelvinLaw, SlopeFloorLeavesThePapersLawUntouchedInsideTheFloor) {
  // k = 1, delta = 0.1: the floor is at lambda = -0.45, far beyond strains of +-0.1, so every number is the
  // paper's law's, bit for bit (the shipped cases' results do not move when a floor is set and not reached).
  const KelvinLaw paper(make_parameters(0.3, 1.0)), floored(with_floor(0.3, 1.0, 0.1));
  EXPECT_DOUBLE_EQ(floored.floor_strain(), -0.45);
  EXPECT_TRUE(std::isinf(paper.floor_strain()));
  std::mt19937 rng(5);
  KelvinState old_state;
  old_state.strain = random_strain(rng, 0.1);
  old_state.viscous_stress = 100.0 * random_strain(rng, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const Vector6 e = random_strain(rng, 0.1);
    EXPECT_EQ(floored.adjusted_strain(e), paper.adjusted_strain(e));
    EXPECT_EQ(floored.adjusted_strain_jacobian(e), paper.adjusted_strain_jacobian(e));
    const KelvinResponse a = paper.update(old_state, e, 0.05), b = floored.update(old_state, e, 0.05);
    EXPECT_EQ(a.stress, b.stress);
    EXPECT_EQ(a.tangent, b.tangent);
    EXPECT_EQ(floored.admissibility_margin(e), paper.admissibility_margin(e));
  }
}

TEST(KelvinLaw, SlopeFloorContinuesTheOneDimensionalLawAlongItsTangent) {
  // nu = 0, uniaxial strain, dt = 0: sigma_xx = K1 n(eps) with n(eps) = eps + k eps^2 down to
  // lambda_c = (delta - 1)/(2k), and n(lambda_c) + delta (eps - lambda_c) past it; the tangent is K1 max(delta,
  // 1 + 2k eps). k = 1, delta = 0.2: lambda_c = -0.4, n(lambda_c) = -0.24.
  const double k1 = 2.0e3;
  const KelvinLaw law(with_floor(0.0, 1.0, 0.2));
  const auto n = [](double eps) { return eps >= -0.4 ? eps + eps * eps : -0.24 + 0.2 * (eps + 0.4); };
  double previous = std::numeric_limits<double>::infinity();
  for (double eps : {0.1, -0.2, -0.39, -0.4, -0.41, -0.5, -0.8, -2.0}) {
    const KelvinResponse r = law.update(KelvinState{}, uniaxial_strain(eps), 0.0);
    EXPECT_NEAR(r.stress(0) / k1, n(eps), 1e-14) << eps;
    EXPECT_NEAR(r.tangent(0, 0) / k1, std::max(0.2, 1.0 + 2.0 * eps), 1e-14) << eps;
    EXPECT_NEAR(r.stress(1), 0.0, 1e-12) << eps;  // nu = 0 and n(0) = 0: no lateral stress
    EXPECT_LT(r.stress(0), previous) << "the stress keeps falling as the strain does: " << eps;
    previous = r.stress(0);
  }
  // Continuous with its slope at lambda_c.
  for (double side : {-1.0, 1.0}) {
    const double eps = -0.4 + side * 1e-9;
    EXPECT_NEAR(law.adjusted_strain(uniaxial_strain(eps))(0), -0.24 + 0.2 * side * 1e-9, 1e-15);
  }
  // k < 0: the floor lies in tension. k = -2, delta = 0.2: lambda_c = 0.2, n(lambda_c) = 0.12.
  const KelvinLaw tensile(with_floor(0.0, -2.0, 0.2));
  EXPECT_DOUBLE_EQ(tensile.floor_strain(), 0.2);
  EXPECT_NEAR(tensile.adjusted_strain(uniaxial_strain(0.3))(0), 0.12 + 0.2 * 0.1, 1e-15);
  EXPECT_NEAR(tensile.adjusted_strain(uniaxial_strain(-0.3))(0), -0.3 - 2.0 * 0.09, 1e-15);
}

TEST(KelvinLaw, SlopeFloorJacobianMatchesFiniteDifferences) {
  // Strains with one, two and three principal strains past the floor (k = 1, delta = 0.1: lambda_c = -0.45),
  // with a pair that straddles it and with a repeated pair, and a tensile floor (k = -1.5).
  const KelvinLaw law(with_floor(0.3, 1.0, 0.1)), tensile(with_floor(0.3, -1.5, 0.1));
  std::mt19937 rng(3);
  std::vector<std::pair<const KelvinLaw*, Vector6>> cases;
  for (double shift : {-0.3, -0.5, -0.7}) {
    for (int trial = 0; trial < 4; ++trial) {
      Vector6 e = random_strain(rng, 0.3);
      e.head<3>().array() += shift;
      cases.emplace_back(&law, e);
    }
  }
  cases.emplace_back(&law, (Vector6() << -0.6, -0.6, 0.1, 0.0, 0.0, 0.0).finished());   // repeated, past
  cases.emplace_back(&law, (Vector6() << -0.46, -0.44, 0.0, 0.0, 0.0, 0.0).finished());  // straddling
  for (int trial = 0; trial < 4; ++trial) {
    Vector6 e = random_strain(rng, 0.3);
    e.head<3>().array() += 0.4;
    cases.emplace_back(&tensile, e);
  }
  int past = 0;
  for (const auto& [l, e] : cases) {
    const bool beyond = (l->parameters().k > 0 ? KelvinLaw::principal_strains(e).minCoeff() < l->floor_strain()
                                               : KelvinLaw::principal_strains(e).maxCoeff() > l->floor_strain());
    past += beyond;
    const Matrix6 jacobian = l->adjusted_strain_jacobian(e);
    const double h = 1e-7;
    Matrix6 fd;
    for (int j = 0; j < 6; ++j) {
      const Vector6 dh = h * Vector6::Unit(j);
      fd.col(j) = (l->adjusted_strain(e + dh) - l->adjusted_strain(e - dh)) / (2.0 * h);
    }
    EXPECT_LT((jacobian - fd).norm() / jacobian.norm(), 1e-7) << e.transpose() << "\nanalytic\n"
                                                              << jacobian << "\nfd\n" << fd;
    // N stays monotone: every eigenvalue of dN/deps is at least delta.
    const Eigen::VectorXcd ev = Eigen::EigenSolver<Matrix6>(jacobian).eigenvalues();
    EXPECT_GT(ev.real().minCoeff(), 0.1 - 1e-10) << e.transpose();
  }
  EXPECT_GE(past, 14) << "most cases must lie past the floor, or the test checks the paper's form only";
}

TEST(KelvinLaw, SlopeFloorIsFrameIndifferentAndAdmitsEveryStrain) {
  const KelvinLaw law(with_floor(0.3, 1.0, 0.1)), paper(make_parameters(0.3, 1.0));
  std::mt19937 rng(13);
  Vector6 strain = random_strain(rng, 0.3);
  strain.head<3>().array() -= 0.5;
  ASSERT_LT(law.admissibility_margin(strain), 0.0) << "the strain must lie past the paper's limit";
  const Matrix3 rotation =
      Eigen::AngleAxisd(1.1, Eigen::Vector3d(-0.4, 0.9, 0.2).normalized()).toRotationMatrix();
  const Matrix3 e = voigt_to_strain(strain);
  const Matrix3 n = voigt_to_strain(law.adjusted_strain(strain));
  const Matrix3 n_rot = voigt_to_strain(law.adjusted_strain(strain_to_voigt(rotation * e * rotation.transpose())));
  EXPECT_LT((n_rot - rotation * n * rotation.transpose()).norm(), 1e-14);
  // The margin still reports the paper's 1 + 2k lambda (where the continuation acted); admits() decides.
  EXPECT_EQ(law.admissibility_margin(strain), paper.admissibility_margin(strain));
  EXPECT_TRUE(law.admits(law.admissibility_margin(strain)));
  EXPECT_FALSE(paper.admits(paper.admissibility_margin(strain)));
  EXPECT_TRUE(paper.admits(0.3));
  // The floor must be in [0, 1), and the message names it.
  for (double bad : {-0.1, 1.0, std::numeric_limits<double>::quiet_NaN()}) {
    try {
      KelvinLaw l(with_floor(0.3, 1.0, bad));
      FAIL() << "accepted slope_floor " << bad;
    } catch (const std::invalid_argument& error) {
      EXPECT_NE(std::string(error.what()).find("slope_floor"), std::string::npos) << error.what();
    }
  }
}

TEST(KelvinLaw, InadmissibleStrainNamesModelTimePointStrainAndRemedies) {
  const KelvinLaw law(make_parameters(0.3, 1.0));
  Vector6 e = Vector6::Zero();
  e << -0.55, 0.1, 0.05, 0.02, 0.0, 0.0;
  const InadmissibleStrain error("FEM reference", 0.4, Eigen::Vector3d(0.2564, 0.0712, -0.3235), e, law);
  const std::string message = error.what();
  std::cout << message << "\n";
  EXPECT_LT(error.margin(), 0.0);
  EXPECT_NEAR(error.margin(), 1.0 + 2.0 * error.principal_strain(), 1e-14);
  EXPECT_LT(error.principal_strain(), -0.55);  // the shear lowers the smallest principal strain below e_xx
  EXPECT_DOUBLE_EQ(error.limit_strain(), -0.5);
  EXPECT_DOUBLE_EQ(error.time(), 0.4);
  for (const char* part : {"FEM reference", "t = 0.4 s", "(256.40, 71.20, -323.50) mm", "-0.5000", "-0.5500",
                           "/load/force", "/material/k", "/load/radius", "/material/slope_floor"})
    EXPECT_NE(message.find(part), std::string::npos) << part;
}

}  // namespace
}  // namespace core
