#include "core/convergence_rate.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace core {

double convergence_rate(const std::vector<double>& h, const std::vector<double>& error) {
  if (h.size() != error.size())
    throw std::invalid_argument("convergence_rate: " + std::to_string(h.size()) + " sizes but " +
                                std::to_string(error.size()) + " errors (one error per size)");
  if (h.size() < 2) throw std::invalid_argument("convergence_rate: a slope needs at least two levels");
  const double n = static_cast<double>(h.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < h.size(); ++i) {
    if (!(h[i] > 0.0) || !(error[i] > 0.0))
      throw std::invalid_argument("convergence_rate: level " + std::to_string(i) +
                                  " has a size or an error that is not positive (no logarithm)");
    const double x = std::log(h[i]), y = std::log(error[i]);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  const double spread = n * sxx - sx * sx;
  if (!(spread > 0.0)) throw std::invalid_argument("convergence_rate: all levels have the same size (no slope)");
  return (n * sxy - sx * sy) / spread;
}

}  // namespace core
