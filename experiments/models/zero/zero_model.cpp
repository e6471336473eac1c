#include "experiments/models/zero/zero_model.hpp"

namespace experiments {

ModelResult ZeroModel::solve(const core::Case&, const core::Geometry& g, const SolveRequest&) const {
  ModelResult r;
  r.model = name();
  r.sample_points = g.sample_points;
  r.sample_displacements = Eigen::MatrixXd::Zero(g.sample_points.rows(), 3);
  describe_samples_near_cut(g, &r);
  return r;
}

}  // namespace experiments
