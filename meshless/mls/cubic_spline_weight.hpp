#pragma once
// The cubic spline weight of the MLS approximation (paper eq. 8).

namespace meshless {

/// Value and slope of the weight at one normalised distance.
struct WeightAndSlope {
  double w = 0.0;      ///< w(s)
  double dw_ds = 0.0;  ///< dw/ds
};

/// Eq. 8: w(s) = 2/3 - 4 s^2 + 4 s^3 for s <= 1/2, 4/3 - 4 s + 4 s^2 - 4/3 s^3 for 1/2 < s <= 1, 0 beyond.
/// s = |X - X_i| / rho_i >= 0 is the distance normalised by the node's support radius. The spline is C2 on
/// [0, inf): value, slope and curvature match at s = 1/2 and vanish at s = 1, which is what makes the MLS
/// shape functions (and their first derivatives, needed by the Galerkin stiffness) continuous.
/// A negative s is treated as |s| (even extension), so callers never get garbage.
double cubic_spline_weight(double s);

/// Eq. 8 and its derivative dw/ds = -8 s + 12 s^2 (s <= 1/2), -4 + 8 s - 4 s^2 (1/2 < s <= 1), 0 beyond.
/// dw/ds(0) = 0, so the weight gradient is well defined at the node itself.
WeightAndSlope cubic_spline_weight_with_slope(double s);

}  // namespace meshless
