#include "experiments/comparator/mesh_study_estimate.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace experiments {
namespace {

/// The observed order of levels a, b, c (coarse to fine) from the norms of their differences; 0 when the
/// differences do not decrease.
double observed_order(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, const Eigen::MatrixXd& c, double ratio) {
  const double d1 = (b - a).norm(), d2 = (c - b).norm();
  return d2 > 0 && d1 > d2 ? std::log(d1 / d2) / std::log(ratio) : 0.0;
}

/// The refinement ratio of levels l - 2, l - 1, l: the mean of its two steps.
double ratio_ending_at(const std::vector<double>& h_mm, std::size_t l) {
  return 0.5 * (h_mm[l - 2] / h_mm[l - 1] + h_mm[l - 1] / h_mm[l]);
}

/// The observed order of each consecutive three levels of `u`.
std::vector<double> orders_of_each_three(const std::vector<Eigen::MatrixXd>& u, const std::vector<double>& h_mm) {
  std::vector<double> orders;
  for (std::size_t l = 2; l < u.size(); ++l)
    orders.push_back(observed_order(u[l - 2], u[l - 1], u[l], ratio_ending_at(h_mm, l)));
  return orders;
}

}  // namespace

double expected_sample_order(const core::Case& c) {
  // header: the smallest of the element's own order, the faceted surface's and the singular lines'
  double order = std::min(c.fem.degree + 1.0, 2.0);
  if (c.fixed_region.support == core::FixedRegionSpec::Support::clamp) order = std::min(order, 1.0);
  if (c.cut) order = std::min(order, c.geometry.crack_front_grading);
  return order;
}

MeshStudyEstimate estimate_remaining_error(const std::vector<Eigen::MatrixXd>& u, const std::vector<double>& h_mm,
                                           double expected_order) {
  if (u.size() != h_mm.size()) throw std::invalid_argument("estimate_remaining_error: one mesh size per level");
  if (!(expected_order > 0.0)) throw std::invalid_argument("estimate_remaining_error: expected order must be > 0");
  MeshStudyEstimate e;
  if (u.size() < 3) return e;
  const std::size_t n = u.size();
  const nlohmann::json orders = orders_of_each_three(u, h_mm);
  const double d2 = (u[n - 1] - u[n - 2]).norm(), finest = u[n - 1].norm();
  const double ratio = ratio_ending_at(h_mm, n - 1);
  const double p = orders.back().get<double>();
  if (d2 == 0.0) {
    e.json = {{"note", "the last two levels agree exactly"}};
    e.sentence = "Richardson: the last two levels agree exactly.";
    return e;
  }
  if (std::abs(p - expected_order) <= kOrderTolerance) {
    const double error = d2 / (std::pow(ratio, p) - 1.0) / finest;
    e.extrapolated = u[n - 1] + (u[n - 1] - u[n - 2]) / (std::pow(ratio, p) - 1.0);
    e.json = {{"kind", "richardson"}, {"observed_order", p}, {"expected_order", expected_order},
              {"estimated_error_of_finest_relative", error}, {"observed_orders", orders}};
    e.sentence = fmt::format("Richardson (last three levels): observed order {:.2f} (expected {:.0f}), estimated "
                             "remaining error of the finest level {:.2f} % of the sample displacements.",
                             p, expected_order, 100 * error);
    return e;
  }
  // Outside the asymptotic range, never the order that would shrink the bar: below the expected order, the data's
  // own (not below kLowestOrder); above it, the expected one.
  const double assumed = p < expected_order ? std::max(p, kLowestOrder) : expected_order;
  const double error = d2 / (std::pow(ratio, assumed) - 1.0) / finest;
  e.extrapolated = u[n - 1] + (u[n - 1] - u[n - 2]) / (std::pow(ratio, assumed) - 1.0);
  const std::string why = p > 0 ? fmt::format("observed order {:.2f} {} the expected {:.0f} ± {}", p,
                                              p < expected_order ? "below" : "above", expected_order, kOrderTolerance)
                                : std::string("differences not decreasing");
  e.json = {{"kind", "assumed_order"},
            {"note", why + ": not in the asymptotic range, or blurred by the noise between non-nested meshes; the "
                           "estimate assumes the smaller of the two orders (at least 1) and is not a bound"},
            {"assumed_order", assumed},
            {"expected_order", expected_order},
            {"estimated_error_of_finest_relative", error},
            {"observed_orders", orders}};
  if (p > 0) e.json["observed_order_not_used"] = p;
  // Gmsh's levels are not nested, so each carries a mesh-dependent part that the order inherits: on the lung cases
  // it spreads the order of 12 / 8 / 5.3 mm over 1 to 2 (docs/FEM_REFERENCE.md, "Mesh-to-mesh noise").
  e.sentence = fmt::format("Richardson: {} (not in the asymptotic range, or blurred by the noise between non-nested "
                           "meshes: docs/FEM_REFERENCE.md, \"Mesh-to-mesh noise\"). Assuming order {:.2f}, the "
                           "remaining error of the finest level is about {:.2f} % of the sample displacements; this is "
                           "an estimate, not a bound.",
                           why, assumed, 100 * error);
  return e;
}

std::string one_mesh_per_level_hint(const MeshStudyEstimate& estimate, int meshes_per_level) {
  if (meshes_per_level != 1 || estimate.json.value("kind", "") != "assumed_order") return {};
  return "One mesh per level: the noise between non-nested meshes can move this order by more than the band; "
         "--meshes-per-level 3 averages it out (docs/FEM_REFERENCE.md, \"The linear lab\").";
}

std::vector<double> observed_orders(const std::vector<Eigen::MatrixXd>& u, const std::vector<double>& h_mm,
                                    const std::vector<Eigen::Index>& rows) {
  if (u.size() != h_mm.size()) throw std::invalid_argument("observed_orders: one mesh size per level");
  std::vector<Eigen::MatrixXd> chosen;
  for (const Eigen::MatrixXd& level : u) chosen.push_back(level(rows, Eigen::all));
  return orders_of_each_three(chosen, h_mm);
}

}  // namespace experiments
