#pragma once
// The observed order of a convergence study: the least-squares slope of log(error) against log(h). Both models'
// verifications (meshless/verification, reference_fem/verification) and the order tests use it, so the slope is
// fitted one way everywhere. Pure function, thread-safe.
#include <vector>

namespace core {

/// Least-squares slope of log(error) against log(h) over the pairs (h[i], error[i]): the order p of error ~ C h^p.
/// Any positive unit for h and error (the slope does not depend on it). Throws std::invalid_argument when the two
/// differ in length, when there are fewer than two pairs, when a value is not positive (no logarithm) or when all
/// h are equal (no slope).
double convergence_rate(const std::vector<double>& h, const std::vector<double>& error);

}  // namespace core
