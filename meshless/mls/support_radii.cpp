#include "meshless/mls/support_radii.hpp"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

#include "meshless/mls/node_search.hpp"

namespace meshless {

SupportRadii::SupportRadii(const core::PointMatrix& nodes, const NodeSearch& search,
                           SupportRadiiParams params)
    : params_(params) {
  if (!(params.d_max > 0.0)) throw std::invalid_argument("SupportRadii: d_max must be > 0");
  if (params.k < 1) throw std::invalid_argument("SupportRadii: k must be >= 1");
  if (search.num_nodes() != nodes.rows())
    throw std::invalid_argument("SupportRadii: the search was built on a different node cloud");
  const Eigen::Index n = nodes.rows();
  if (n < params.k + 1)
    throw std::invalid_argument(
        fmt::format("SupportRadii: {} nodes, but k = {} needs at least {}", n, params.k, params.k + 1));

  radii_.resize(n);
  std::vector<double> d2;
  for (Eigen::Index i = 0; i < n; ++i) {
    // Ask for k + 1: the node itself comes back at distance 0. Taking entry k of the sorted list is right
    // even when other nodes coincide with i (they also sit at 0 and one of them stands in for i).
    search.nearest(nodes.row(i).transpose(), params.k + 1, &d2);
    const double rho = params.d_max * std::sqrt(d2.at(static_cast<size_t>(params.k)));
    if (!(rho > 0.0))
      throw std::invalid_argument(fmt::format(
          "SupportRadii: node {} at ({:.6g}, {:.6g}, {:.6g}) mm has {} coincident nodes; rho would be 0", i,
          1e3 * nodes(i, 0), 1e3 * nodes(i, 1), 1e3 * nodes(i, 2), params.k));
    radii_[i] = rho;
  }
  max_radius_ = radii_.maxCoeff();
}

SupportRadii::SupportRadii(Eigen::VectorXd radii) : radii_(std::move(radii)) {
  if (radii_.size() == 0) throw std::invalid_argument("SupportRadii: no radii");
  if (!(radii_.array() > 0.0).all() || !radii_.allFinite())
    throw std::invalid_argument("SupportRadii: every radius must be finite and > 0");
  max_radius_ = radii_.maxCoeff();
  params_.d_max = 0.0;  // unknown: the radii were not derived from the cloud
  params_.k = 0;
}

bool SupportRadii::covers(int node, const core::PointMatrix& nodes, const Eigen::Vector3d& x) const {
  const double rho = radii_[node];
  return (x - nodes.row(node).transpose()).squaredNorm() < rho * rho;
}

}  // namespace meshless
