#include "meshless/mls/cubic_spline_weight.hpp"

#include <cmath>

namespace meshless {

double cubic_spline_weight(double s) {
  s = std::abs(s);
  if (s <= 0.5) return 2.0 / 3.0 - 4.0 * s * s + 4.0 * s * s * s;
  if (s <= 1.0) {
    const double t =
        1.0 - s;  // 4/3 - 4 s + 4 s^2 - 4/3 s^3 = 4/3 (1-s)^3, factored to avoid cancellation near s=1
    return 4.0 / 3.0 * t * t * t;
  }
  return 0.0;
}

WeightAndSlope cubic_spline_weight_with_slope(double s) {
  // Even extension: w(-s) = w(s), so dw/ds flips sign for negative s.
  const double sign = s < 0.0 ? -1.0 : 1.0;
  s = std::abs(s);
  WeightAndSlope out;
  if (s <= 0.5) {
    out.w = 2.0 / 3.0 - 4.0 * s * s + 4.0 * s * s * s;
    out.dw_ds = -8.0 * s + 12.0 * s * s;
  } else if (s <= 1.0) {
    const double t = 1.0 - s;  // see cubic_spline_weight()
    out.w = 4.0 / 3.0 * t * t * t;
    out.dw_ds = -4.0 * t * t;
  }
  out.dw_ds *= sign;
  return out;
}

}  // namespace meshless
