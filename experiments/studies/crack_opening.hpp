#pragma once
// The crack-opening verification of the meshless cut (docs/MESHLESS.md §5): a block 40 x 20 x 20 mm with a
// surface-breaking crack (the plane y = 10 mm, 10 <= x <= 30 mm, from the top face down 10 mm), clamped on y = 0 and
// pulled by 60 Pa on y = 20 mm (mode I, elastic step, k = 0). The FEM reference cracks it with duplicated nodes
// (core/crack_embedding.hpp), the EFG model enriches or shadows its weights (meshless/cut/cut_weights.hpp): both use the
// same core::RuledSurface. Used by tests/test_cut_opening.cpp and `tissue verify meshless`.
#include <Eigen/Core>
#include <vector>

#include "core/ruled_surface.hpp"
#include "meshless/cut/cut_weights.hpp"

namespace experiments {

/// The block's crack (its normal is +y: the s > 0 lip is the pulled side).
core::RuledSurface crack_opening_cut();

/// Points on the crack where the opening is compared: the vertical centre line x = 20 mm from the mouth (z = 19.5 mm)
/// to the front (z = 10.5 mm), then the line at half depth (z = 15 mm) from x = 10.5 to 28.5 mm. [m]
std::vector<Eigen::Vector3d> crack_opening_profile();

/// The FEM reference's opening u_y(+) - u_y(-) [m] at the profile points: P2 on the cracked block meshed at `size`.
std::vector<double> fem_crack_opening(double size, std::size_t* dofs = nullptr);

/// The EFG model's opening [m] at the profile points, on a jittered box cloud of about `spacing` [m] (an odd number
/// of cells across y, so no node plane lies on the crack) with the given treatment and front transition l [m].
std::vector<double> efg_crack_opening(meshless::CutTreatment treatment, double spacing, double front_transition,
                                      int* nodes = nullptr);

/// max_k |a_k - b_k| / max_k b_k: the largest difference as a fraction of the reference's peak.
double largest_difference_of_peak(const std::vector<double>& a, const std::vector<double>& reference);

}  // namespace experiments
