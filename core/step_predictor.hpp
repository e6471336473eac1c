#pragma once
// When a Newton solve may start from the extrapolated state U_n + (dt_{n+1} / dt_n)(U_n - U_{n-1}) instead of U_n
// (EfgOptions::extrapolate_start, LrpimProblem::extrapolate_start, reference_fem::NewtonParameters::extrapolate_start;
// docs/MESHLESS.md §2): only while the load keeps its rate over the two steps, on a ramp or in a hold. At the end of a
// ramp the last increment is no guide. All three models share this rule. Stateless; the caller keeps U_{n-1} and the
// times.
#include <algorithm>
#include <cmath>
#include <functional>

namespace core {

/// True when t_before < t_from < t_to and the load scale s(t) changes at one rate over [t_before, t_from] and
/// [t_from, t_to], to a relative 1e-6 (step times are sums, equal rates differ in their last bits).
inline bool load_keeps_its_rate(const std::function<double(double)>& load_scale, double t_before, double t_from,
                                double t_to) {
  const double dt_before = t_from - t_before, dt = t_to - t_from;
  if (!(dt_before > 0.0) || !(dt > 0.0)) return false;
  auto s = [&](double t) { return load_scale ? load_scale(t) : 1.0; };
  const double rate_before = (s(t_from) - s(t_before)) / dt_before;
  const double rate = (s(t_to) - s(t_from)) / dt;
  return std::abs(rate - rate_before) <= 1e-6 * std::max({std::abs(rate), std::abs(rate_before), 1e-300});
}

}  // namespace core
