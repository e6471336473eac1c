#include "meshless/solvers/kept_factors.hpp"

#include <cmath>

namespace meshless {

bool kept_factors_too_slow(double rn, double last, double run_start, int run_length, double target, int iteration,
                           double contraction, int max_iterations) {
  if (run_length == 0) return false;  // nothing measured on these factors yet
  if (!(rn < last)) return true;
  // lung_small's LRPIM step 4 (README command 1): 0.07, 0.07, 0.02, then 0.53 an iteration short of the tolerance.
  const double rate = std::pow(rn / run_start, 1.0 / run_length);
  if (rate > contraction) return true;
  // At that rate the residual reaches the target after log(target / rn) / log(rate) more updates.
  return rn > target && iteration + std::log(rn / target) / -std::log(rate) > max_iterations;
}

}  // namespace meshless
