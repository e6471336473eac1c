#include "experiments/mesh_study_estimate.hpp"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

namespace experiments {

MeshStudyEstimate estimate_remaining_error(const std::vector<Eigen::MatrixXd>& u, const std::vector<double>& h_mm) {
  if (u.size() != h_mm.size()) throw std::invalid_argument("estimate_remaining_error: one mesh size per level");
  MeshStudyEstimate e;
  if (u.size() < 3) return e;
  const std::size_t n = u.size();
  const double d1 = (u[n - 2] - u[n - 3]).norm(), d2 = (u[n - 1] - u[n - 2]).norm(), finest = u[n - 1].norm();
  const double ratio = 0.5 * (h_mm[n - 3] / h_mm[n - 2] + h_mm[n - 2] / h_mm[n - 1]);
  constexpr double kAsymptoticOrder = 1.0;  // header
  const double p = d2 > 0 && d1 > d2 ? std::log(d1 / d2) / std::log(ratio) : 0.0;
  if (p >= kAsymptoticOrder) {
    const double error = d2 / (std::pow(ratio, p) - 1.0) / finest;
    e.json = {{"observed_order", p}, {"estimated_error_of_finest_relative", error}};
    e.sentence = fmt::format("Richardson (last three levels): observed order {:.2f}, estimated remaining error of the "
                             "finest level {:.2f} % of the sample displacements.",
                             p, 100 * error);
  } else if (d2 > 0) {
    // Extrapolating with an order below the asymptotic one would blow the estimate up (order 0.2 gives 28 %).
    const double error = d2 / (std::pow(ratio, kAsymptoticOrder) - 1.0) / finest;
    const std::string why =
        p > 0 ? fmt::format("observed order {:.2f} below 1", p) : std::string("differences not decreasing");
    e.json = {{"note", why + ": not yet asymptotic; order 1 assumed for a bound"},
              {"assumed_order", kAsymptoticOrder},
              {"estimated_error_of_finest_relative", error}};
    if (p > 0) e.json["observed_order_not_used"] = p;
    e.sentence = fmt::format("Richardson: {} (not yet asymptotic). Assuming first-order convergence, the remaining "
                             "error of the finest level is at most about {:.2f} % of the sample displacements.",
                             why, 100 * error);
  } else {
    e.json = {{"note", "the last two levels agree exactly"}};
    e.sentence = "Richardson: the last two levels agree exactly.";
  }
  return e;
}

}  // namespace experiments
