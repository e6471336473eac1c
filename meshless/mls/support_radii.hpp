#pragma once
// Per-node radii of the influence spheres rho_i that normalise the weight of eq. 8 (s_i = |X - X_i| / rho_i).
#include <Eigen/Core>

#include "core/tet_mesh.hpp"

namespace meshless {

class NodeSearch;

/// How rho_i is chosen: rho_i = d_max * (distance from node i to its k-th nearest other node).
///
/// Why k = 8 by default (not 6): the linear basis P = [1, x, y, z] (eq. 1) needs every evaluation point to be
/// covered by at least 4 non-coplanar nodes, and in practice by clearly more for A(X) (eq. 3) to be well
/// conditioned. k sets the spacing estimate: on a regular grid of spacing a the 6 face neighbours sit at a
/// and the next 12 at a*sqrt(2), so k = 6 gives rho = 2a and k = 8 gives rho = 2*sqrt(2)*a (inside the usual
/// EFG range of 2a..4a). With k = 6 a node whose closest neighbours happen to lie on one side (irregular
/// clouds, or a surface sampled finer than the interior) gets a small sphere; averaging over a few more
/// neighbours makes rho less sensitive to that. Measured with d_max = 2 over 20000 points spread over the
/// whole box (corners included) of 1331-node clouds in a 0.1 m cube, worst rcond of the scaled A(X) /
/// fewest covering nodes, for k = 6 -> 8 -> 10:
///   uniform random     1.6e-4 / 8  -> 4.3e-4 / 8  -> 8.3e-4 / 14
///   graded random      2.8e-4 / 8  -> 5.4e-4 / 12 -> 9.9e-4 / 17
///   layered, 4x finer in-plane than across (18k nodes)  4.7e-5 / 13 -> 1.2e-4 / 21 -> 1.5e-4 / 27
/// while the mean number of covering nodes (the cost driver: stiffness assembly is quadratic in it) grows
/// 42 -> 55 -> 68 on the uniform cloud. k = 8 roughly doubles the worst-case conditioning of k = 6 at ~30%
/// more neighbours, and stays 6 orders above the 1e-10 singularity threshold everywhere tested.
/// d_max = 2 is the usual EFG dilation parameter.
struct SupportRadiiParams {
  double d_max = 2.0;  ///< dilation factor, dimensionless
  int k = 8;           ///< which nearest other node sets the local nodal spacing
};

/// rho_i for every node of a cloud, plus their maximum (the radius of the candidate query around an
/// evaluation point: any node covering X lies within max_radius() of X).
class SupportRadii {
 public:
  /// @param nodes #nodes by 3, metres (the same matrix `search` was built on)
  /// @param search KD-tree over `nodes`
  /// @throws std::invalid_argument if the cloud has fewer than k + 1 nodes, d_max <= 0, k < 1, or two nodes
  ///         coincide so that some rho_i would be 0
  SupportRadii(const core::PointMatrix& nodes, const NodeSearch& search, SupportRadiiParams params = {});

  /// Radii given directly (e.g. read back from a run), #nodes entries, metres, all > 0.
  explicit SupportRadii(Eigen::VectorXd radii);

  const Eigen::VectorXd& radii() const { return radii_; }  ///< #nodes, metres
  double radius(int node) const { return radii_[node]; }   ///< rho_node [m]
  double max_radius() const { return max_radius_; }        ///< max_i rho_i [m]
  int size() const { return static_cast<int>(radii_.size()); }
  const SupportRadiiParams& params() const { return params_; }

  /// True when node `node` covers X, i.e. |X - X_node| < rho_node (strict: w(1) = 0 anyway).
  bool covers(int node, const core::PointMatrix& nodes, const Eigen::Vector3d& x) const;

 private:
  Eigen::VectorXd radii_;
  double max_radius_ = 0.0;
  SupportRadiiParams params_;
};

}  // namespace meshless
