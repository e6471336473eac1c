#pragma once
// The FEM reference's remaining discretisation error at the samples, from a mesh study's last three levels
// (tissue verify fem; the comparator's error bar, experiments/compare_metrics.hpp).
#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace experiments {

struct MeshStudyEstimate {
  /// {observed_order, estimated_error_of_finest_relative} for a Richardson estimate, or {note, assumed_order,
  /// estimated_error_of_finest_relative[, observed_order_not_used]} for the first-order bound, or {note} when
  /// the last two levels agree exactly. Empty with fewer than three levels.
  nlohmann::json json;
  std::string sentence;  ///< the same for fem.md
};

/// `u[l]`: every sample displacement of level l (any shape, same for all levels), `h_mm[l]` its mesh size,
/// coarse to fine. The samples converge at order 1 once asymptotic (the clamp's edge, an r^(1/2)
/// singularity, limits the displacements away from it to order 2 x 1/2; docs/FEM_REFERENCE.md), so an observed
/// order of at least 1 is extrapolated with, and anything less (a coarse level not yet asymptotic, or
/// differences that do not shrink) gives the first-order bound instead. The error is relative to the finest
/// level's norm.
MeshStudyEstimate estimate_remaining_error(const std::vector<Eigen::MatrixXd>& u, const std::vector<double>& h_mm);

}  // namespace experiments
