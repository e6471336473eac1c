// core::convergence_rate, the least-squares order every convergence test and `verify` fits: exact on a power law,
// independent of the units, the two-level slope of a mixed law, and refusals that say what is wrong.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "core/convergence_rate.hpp"

namespace core {
namespace {

TEST(ConvergenceRate, RecoversThePowerOfAnExactPowerLaw) {
  const std::vector<double> h = {4.0, 2.0, 1.0, 0.5};
  for (double p : {1.0, 2.5, 3.7}) {
    std::vector<double> error;
    for (double x : h) error.push_back(0.3 * std::pow(x, p));
    EXPECT_NEAR(convergence_rate(h, error), p, 1e-12);
  }
}

TEST(ConvergenceRate, DoesNotDependOnTheUnitsOfSizeOrError) {
  const std::vector<double> h = {27.0, 18.0, 12.0, 8.0};
  const std::vector<double> error = {3.25, 1.49, 0.54, 0.13};
  std::vector<double> h_m, error_scaled;
  for (double x : h) h_m.push_back(1e-3 * x);
  for (double e : error) error_scaled.push_back(7.0 * e);
  EXPECT_NEAR(convergence_rate(h_m, error_scaled), convergence_rate(h, error), 1e-12);
}

TEST(ConvergenceRate, TwoLevelsGiveTheirOwnSlope) {
  // error = h^2 + h^3 at h = 1 and 1/2: the observed order is log2(2 / (1/4 + 1/8)) = log2(16 / 3) = 2.415.
  EXPECT_NEAR(convergence_rate({1.0, 0.5}, {2.0, 0.375}), std::log2(16.0 / 3.0), 1e-12);
}

TEST(ConvergenceRate, RefusesWhatHasNoSlope) {
  EXPECT_THROW(convergence_rate({1.0, 0.5}, {1.0}), std::invalid_argument);      // one error per size
  EXPECT_THROW(convergence_rate({1.0}, {1.0}), std::invalid_argument);           // one level
  EXPECT_THROW(convergence_rate({1.0, 0.5}, {1.0, 0.0}), std::invalid_argument); // log(0)
  EXPECT_THROW(convergence_rate({1.0, 1.0}, {1.0, 0.5}), std::invalid_argument); // equal sizes
}

}  // namespace
}  // namespace core
