// The step cut-back and the Newton divergence test shared by both models (core/step_cutback.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#include "core/step_cutback.hpp"

namespace core {
namespace {

/// A model whose Newton converges only on steps no longer than `largest`; it records every call.
struct FakeModel {
  double largest = 1.0;
  double committed = 0.0;  // the time of the committed state
  std::vector<std::pair<double, double>> calls;
  NewtonAttempt operator()(double from, double to) {
    EXPECT_EQ(from, committed) << "an attempt must start from the committed state";
    calls.push_back({from, to});
    NewtonAttempt a;
    a.t_start = from;
    a.t_end = to;
    a.iterations = 3;
    a.residuals = {1.0, 0.5, 2.0};
    if (to - from > largest * (1 + 1e-12)) {
      a.failure = "the iteration limit was reached";
    } else {
      committed = to;
      a.residuals = {1.0, 1e-3, 1e-9};
    }
    return a;
  }
};

TEST(StepCutback, ConvergedStepIsOneAttemptOverTheWholeStep) {
  FakeModel m;
  m.committed = 0.2;
  const CutBackRecord r = advance_with_cutback("model", 0.2, 0.4, 0.01, std::ref(m));
  ASSERT_EQ(m.calls.size(), 1u);
  // exactly the requested times: results at them are those of plain stepping
  EXPECT_EQ(m.calls[0].first, 0.2);
  EXPECT_EQ(m.calls[0].second, 0.4);
  EXPECT_EQ(r.substeps, 1);
  EXPECT_EQ(r.cutbacks, 0);
  EXPECT_TRUE(r.failures.empty());
}

TEST(StepCutback, HalvesUntilNewtonConvergesAndEndsExactlyAtTheRequestedTime) {
  FakeModel m;
  m.largest = 0.06;  // the step of 0.2 s needs two halvings: 0.1 fails, 0.05 converges
  m.committed = 0.2;
  const CutBackRecord r = advance_with_cutback("model", 0.2, 0.4, 0.01, std::ref(m));
  EXPECT_EQ(r.cutbacks, 2);
  EXPECT_EQ(r.substeps, 4);
  ASSERT_EQ(r.failures.size(), 2u);
  EXPECT_NEAR(r.failures[0].t_end - r.failures[0].t_start, 0.2, 1e-15);
  EXPECT_NEAR(r.failures[1].t_end - r.failures[1].t_start, 0.1, 1e-15);
  ASSERT_EQ(m.calls.size(), 6u);          // 0.2 and 0.1 fail, then four sub-steps of 0.05
  EXPECT_EQ(m.calls.back().second, 0.4);  // the last sub-step ends at t_end, not at a rounded sum
  EXPECT_EQ(m.committed, 0.4);
  EXPECT_NEAR(r.smallest_step, 0.05, 1e-15);
}

TEST(StepCutback, FailsWithEveryAttemptBelowTheMinimumStep) {
  FakeModel m;
  m.largest = 0.01;
  try {
    advance_with_cutback("meshless (EFG) model 'x'", 0.0, 0.2, 0.04, std::ref(m));
    FAIL() << "expected StepCutBackFailed";
  } catch (const StepCutBackFailed& e) {
    const std::string message = e.what();
    std::cout << message << "\n";
    // 0.2, 0.1 and 0.05 fail; 0.025 would be below the minimum of 0.04
    ASSERT_EQ(e.attempts().size(), 3u);
    EXPECT_EQ(m.committed, 0.0);
    EXPECT_DOUBLE_EQ(e.min_step(), 0.04);
    for (const char* part :
         {"meshless (EFG) model 'x'", "t = 0 s to t = 0.2 s", "/time/min_step",
          "t = 0 -> 0.05 s (dt = 0.05 s): the iteration limit was reached after 3 iterations",
          "last relative residual 2", "/time/steps", "/load/force"})
      EXPECT_NE(message.find(part), std::string::npos) << part;
  }
}

TEST(StepCutback, DisabledOrZeroLengthStepFailsAtOnce) {
  FakeModel m;
  m.largest = 0.01;
  EXPECT_THROW(advance_with_cutback("model", 0.0, 0.2, 0.0, std::ref(m)), StepCutBackFailed);
  EXPECT_EQ(m.calls.size(), 1u);
  FakeModel instant;
  instant.largest = -1.0;  // even a zero-length step fails
  EXPECT_THROW(advance_with_cutback("model", 0.0, 0.0, 0.01, std::ref(instant)), StepCutBackFailed);
  EXPECT_EQ(instant.calls.size(), 1u);
}

// An attempt that fails after an iterate outside the law's admissible range is cut back like any failure; when
// the minimum step fails with such an iterate, the run stops with that InadmissibleStrain (its point and strain),
// not with the list of attempts. An inadmissible iterate in an attempt that converges is no error.
TEST(StepCutback, InadmissibleIterateIsCutBackThenReportedAtTheMinimumStep) {
  const KelvinLaw law(KelvinParameters{2000.0, 1000.0, 600.0, 0.3, 1.0});
  Vector6 strain = Vector6::Zero();
  strain[2] = -0.6;  // 1 + 2k lambda = -0.2
  const auto outside = std::make_shared<const InadmissibleStrain>("FEM reference", 0.1, Eigen::Vector3d(0.01, 0.02, 0.03),
                                                                  strain, law);
  int calls = 0;
  const auto failing = [&](double from, double to) {
    ++calls;
    NewtonAttempt a;
    a.t_start = from;
    a.t_end = to;
    a.failure = "diverging";
    if (calls == 2) a.inadmissible = outside;  // only the second of three attempts met it
    return a;
  };
  EXPECT_THROW(advance_with_cutback("FEM reference", 0.0, 0.2, 0.04, failing), StepCutBackFailed)
      << "the last attempt met no inadmissible iterate";
  calls = 1;  // the next call is the second: it meets the inadmissible iterate
  try {
    advance_with_cutback("FEM reference", 0.0, 0.2, 0.2, failing);
    FAIL() << "expected InadmissibleStrain";
  } catch (const InadmissibleStrain& e) {
    EXPECT_EQ(calls, 2) << "only the whole step was tried: 0.1 is below the minimum";
    EXPECT_DOUBLE_EQ(e.margin(), outside->margin());
    EXPECT_EQ(e.point(), outside->point());
    EXPECT_NEAR(e.margin(), -0.2, 1e-14);  // Measured 5.6e-17
  }
  const auto converging = [&](double from, double to) {
    NewtonAttempt a;
    a.t_start = from;
    a.t_end = to;
    a.inadmissible = outside;  // a transient iterate; the model clears it on convergence, but it must not matter
    a.failure.clear();
    return a;
  };
  EXPECT_EQ(advance_with_cutback("FEM reference", 0.0, 0.2, 0.04, converging).substeps, 1);
}

TEST(DivergenceTest, StopsOnNonFiniteGrowthAndRepeatedIncrease) {
  const DivergenceTest test;  // growth 1e3, 4 consecutive increases
  // Quadratic convergence, and a first iteration that overshoots, are not divergence.
  EXPECT_EQ(test({1.0, 0.3, 2e-2, 1e-4, 1e-9}), "");
  EXPECT_EQ(test({1.0, 5.0, 0.2, 1e-3}), "");
  EXPECT_NE(test({1.0, 0.1, std::numeric_limits<double>::quiet_NaN()}).find("not finite"), std::string::npos);
  EXPECT_NE(test({1.0, std::numeric_limits<double>::infinity()}).find("not finite"), std::string::npos);
  // 1e3-fold over the smallest residual of the attempt, not over the first
  EXPECT_EQ(test({1.0, 1e-3, 0.9}), "");
  EXPECT_NE(test({1.0, 1e-3, 1.1}).find("grew"), std::string::npos);
  EXPECT_NE(test({1.0, 1e-2, 2e-2, 4e-2, 8e-2, 1.6e-1}).find("4 consecutive"), std::string::npos);
  EXPECT_EQ(test({1.0, 1e-2, 2e-2, 4e-2, 8e-2}), "");  // three increases only
}

}  // namespace
}  // namespace core
