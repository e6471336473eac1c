#pragma once
// The consistency check shared by every linearly complete shape function family (the EFG's MLS, the LRPIM's RPIM):
// partition of unity, linear reproduction and their derivatives, recorded as the worst error over the points seen.
// `tissue verify meshless` and `tissue verify lrpim` report it (docs/MESHLESS.md §3, docs/LRPIM.md §4).
#include <Eigen/Core>
#include <vector>

#include "core/tet_mesh.hpp"

namespace meshless {

/// The worst consistency errors of a linearly complete shape function family (MLS, RPIM) over the points recorded.
/// A plain value: not thread-safe to record into from several threads at once.
struct InvariantReport {
  int num_nodes = 0, num_points = 0;
  double max_partition_error = 0.0;        ///< max |sum phi_i - 1|
  double max_reproduction_error = 0.0;     ///< max |sum phi_i X_i - X| / node spacing
  double max_gradient_sum = 0.0;           ///< max |sum grad phi_i| * node spacing
  double max_gradient_reproduction = 0.0;  ///< max |sum X_i (x) grad phi_i - I|

  /// Keeps the errors at `x` of the shape functions `phi` (and gradients `dphi`, 3 by #n, 1/m) of the nodes
  /// `node_ids` (rows of `nodes`, m) where they exceed those recorded. `spacing` [m] makes the reproduction and
  /// gradient-sum errors dimensionless.
  void record(const core::PointMatrix& nodes, const Eigen::Vector3d& x, const std::vector<int>& node_ids,
              const Eigen::VectorXd& phi, const Eigen::Matrix<double, 3, Eigen::Dynamic>& dphi, double spacing);
};

}  // namespace meshless
