#include "meshless/verification/invariant_report.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace meshless {

void InvariantReport::record(const core::PointMatrix& nodes, const Eigen::Vector3d& x, const std::vector<int>& node_ids,
                             const Eigen::VectorXd& phi, const Eigen::Matrix<double, 3, Eigen::Dynamic>& dphi,
                             double spacing) {
  double sum = 0.0;
  Eigen::Vector3d reproduced = Eigen::Vector3d::Zero(), gradient_sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d gradient_reproduced = Eigen::Matrix3d::Zero();
  for (std::size_t k = 0; k < node_ids.size(); ++k) {
    const Eigen::Vector3d xi = nodes.row(node_ids[k]).transpose();
    sum += phi[k];
    reproduced += phi[k] * xi;
    gradient_sum += dphi.col(k);
    gradient_reproduced += xi * dphi.col(k).transpose();
  }
  max_partition_error = std::max(max_partition_error, std::abs(sum - 1.0));
  max_reproduction_error = std::max(max_reproduction_error, (reproduced - x).norm() / spacing);
  max_gradient_sum = std::max(max_gradient_sum, gradient_sum.norm() * spacing);
  max_gradient_reproduction =
      std::max(max_gradient_reproduction, (gradient_reproduced - Eigen::Matrix3d::Identity()).norm());
}

}  // namespace meshless
