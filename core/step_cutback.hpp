#pragma once
// Time-step cut-back shared by both models, and the Newton divergence test they both apply.
//
// A model advances from t_n to t_{n+1} with Newton's method. When an attempt fails (too many iterations, a
// diverging or non-finite residual, a failed linear solve), advance_with_cutback() halves the step and tries
// again from t_n, down to a minimum step; sub-steps then run at that size until t_{n+1} is reached. When the
// minimum step fails too it throws StepCutBackFailed with every attempt.
//
// The law's admissible range (core::InadmissibleStrain, docs/MATERIAL.md §1.5) is checked at every iterate, but
// an iterate outside it is not an error by itself: Newton's transient iterates can overshoot where the
// converged state does not. The models raise InadmissibleStrain when a *converged* state is outside the range
// (no step size helps), and a failed attempt carries the first inadmissible iterate it met; when the cut-back
// is exhausted and the last failure carries one, advance_with_cutback() throws it instead of
// StepCutBackFailed, because that strain is why Newton failed.
//
// When the first attempt converges, advance_with_cutback() makes exactly one call, attempt(t_n, t_{n+1}), so
// results at the requested times are those of plain stepping.
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/inadmissible_strain.hpp"

namespace core {

/// One Newton solve of a step or sub-step, and how it ended.
struct NewtonAttempt {
  double t_start = 0.0;           ///< [s]
  double t_end = 0.0;             ///< [s]
  int iterations = 0;             ///< linear solves
  std::vector<double> residuals;  ///< relative residual before each solve (and the converged one)
  std::string failure;            ///< why Newton stopped; empty when it converged
  /// A failed attempt's first iterate outside the law's admissible range, if it met one (null otherwise).
  std::shared_ptr<const InadmissibleStrain> inadmissible;
  bool converged() const { return failure.empty(); }
};

/// Early detection of a diverging Newton iteration from its relative residuals: it stops as soon as the
/// residual is not finite, exceeds `growth_limit` times the smallest residual of the attempt, or has grown
/// in `max_increases` consecutive iterations. Returns why, or an empty string while the iteration may go on.
struct DivergenceTest {
  double growth_limit = 1e3;
  int max_increases = 4;
  std::string operator()(const std::vector<double>& residuals) const;
};

/// How a requested step was completed.
struct CutBackRecord {
  int substeps = 0;                     ///< converged (sub-)steps; 1 without cut-back
  int cutbacks = 0;                     ///< halvings of the step
  double smallest_step = 0.0;           ///< [s] size of the smallest converged sub-step
  std::vector<NewtonAttempt> failures;  ///< the attempts that failed, in order
};

/// Thrown when a step fails even at the minimum step. Names the model, the step and every attempt.
class StepCutBackFailed : public std::runtime_error {
 public:
  StepCutBackFailed(const std::string& model, double t_start, double t_end, double min_step,
                    std::vector<NewtonAttempt> attempts);
  const std::string& model() const { return model_; }
  double t_start() const { return t_start_; }
  double t_end() const { return t_end_; }
  double min_step() const { return min_step_; }
  const std::vector<NewtonAttempt>& attempts() const { return attempts_; }

 private:
  std::string model_;
  double t_start_, t_end_, min_step_;
  std::vector<NewtonAttempt> attempts_;
};

/// Advance from t_start to t_end in one step, or in halved sub-steps when Newton fails.
/// `attempt(t_from, t_to)` runs Newton from the model's committed state at t_from; when it converges it must
/// commit the state at t_to, and when it fails it must leave the committed state at t_from untouched.
/// min_step <= 0 disables the cut-back (the first failure throws). A step of zero length (an instantaneous
/// load at t = 0) cannot be halved.
/// @throws StepCutBackFailed when a sub-step shorter than 2 min_step fails
/// @throws InadmissibleStrain instead, when that last failed attempt met an inadmissible iterate
CutBackRecord advance_with_cutback(const std::string& model, double t_start, double t_end, double min_step,
                                   const std::function<NewtonAttempt(double t_from, double t_to)>& attempt);

}  // namespace core
