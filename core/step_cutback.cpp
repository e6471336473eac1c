#include "core/step_cutback.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace core {

std::string DivergenceTest::operator()(const std::vector<double>& residuals) const {
  if (residuals.empty()) return {};
  const double last = residuals.back();
  if (!std::isfinite(last)) return "the residual is not finite";
  const double smallest = *std::min_element(residuals.begin(), residuals.end());
  if (last > growth_limit * smallest)
    return fmt::format("diverging: the residual grew {:.3g}-fold over the smallest of the step",
                       last / smallest);
  const int n = static_cast<int>(residuals.size());
  if (n > max_increases) {
    bool growing = true;
    for (int i = n - max_increases; i < n; ++i) growing = growing && residuals[i] > residuals[i - 1];
    if (growing)
      return fmt::format("diverging: the residual grew in {} consecutive iterations", max_increases);
  }
  return {};
}

namespace {

std::string describe(const std::string& model, double t_start, double t_end, double min_step,
                     const std::vector<NewtonAttempt>& attempts) {
  std::string text = fmt::format(
      "{}: Newton did not converge on the step from t = {:.6g} s to t = {:.6g} s, even after halving it to "
      "the "
      "minimum step of {:.3g} s (/time/min_step). Attempts:",
      model, t_start, t_end, min_step);
  for (const NewtonAttempt& a : attempts) {
    text += fmt::format("\n  t = {:.6g} -> {:.6g} s (dt = {:.3g} s): {} after {} iterations", a.t_start,
                        a.t_end, a.t_end - a.t_start, a.failure, a.iterations);
    if (!a.residuals.empty()) text += fmt::format(", last relative residual {:.3g}", a.residuals.back());
  }
  text +=
      "\nThe load changes too fast for the time step, or the body has no equilibrium nearby. What to change: "
      "more "
      "time steps (/time/steps) or a smaller /time/min_step, a slower load ramp (/load/ramp_time), a lower "
      "force "
      "(/load/force) or k (/material/k), or a larger load patch (/load/radius)";
  return text;
}

}  // namespace

StepCutBackFailed::StepCutBackFailed(const std::string& model, double t_start, double t_end, double min_step,
                                     std::vector<NewtonAttempt> attempts)
    : std::runtime_error(describe(model, t_start, t_end, min_step, attempts)),
      model_(model),
      t_start_(t_start),
      t_end_(t_end),
      min_step_(min_step),
      attempts_(std::move(attempts)) {}

CutBackRecord advance_with_cutback(const std::string& model, double t_start, double t_end, double min_step,
                                   const std::function<NewtonAttempt(double, double)>& attempt) {
  CutBackRecord record;
  double t = t_start;
  double step = t_end - t_start;
  record.smallest_step = step;
  // Sub-steps end exactly at t_end: a remainder within round-off of the step is absorbed.
  const double slack = 1e-9 * std::max(step, 0.0);
  do {
    const double t_next = (t_end - t <= step + slack) ? t_end : t + step;
    NewtonAttempt a = attempt(t, t_next);
    if (a.converged()) {
      ++record.substeps;
      record.smallest_step = std::min(record.smallest_step, t_next - t);
      t = t_next;
      continue;
    }
    record.failures.push_back(std::move(a));
    const double half = 0.5 * (t_next - t);
    if (!(min_step > 0.0) || half < min_step * (1.0 - 1e-9) || !(half > 0.0)) {
      if (record.failures.back().inadmissible) throw InadmissibleStrain(*record.failures.back().inadmissible);
      throw StepCutBackFailed(model, t_start, t_end, min_step, record.failures);
    }
    step = half;
    ++record.cutbacks;
  } while (t < t_end);
  return record;
}

}  // namespace core
