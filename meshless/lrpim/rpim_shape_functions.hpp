#pragma once
// Radial point interpolation (RPIM) shape functions of the LRPIM model: a multiquadric radial basis augmented
// with the linear polynomial [1, x, y, z] (Liu & Gu 2001, "A local radial point interpolation method (LRPIM)
// for free vibration analyses of 2-D solids", J. Sound Vib. 246(1); Liu & Gu 2005, "An Introduction to Meshfree
// Methods and Their Programming", ch. 3). Unlike the EFG's MLS (meshless/mls/mls_shape_functions.hpp), these
// functions interpolate: phi_i(X_j) = delta_ij, so essential conditions are imposed by setting nodal values.
#include <Eigen/Core>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "core/tet_mesh.hpp"

namespace meshless {
class NodeSearch;
}

namespace meshless::lrpim {

/// Thrown when the augmented moment matrix G = [R P; P^T 0] at an evaluation point cannot be solved reliably:
/// the n nearest nodes are (nearly) coplanar so that the linear block P does not have full column rank, or the
/// multiquadric block is too flat for double precision. The message names the point and what to change.
class SingularRpimMatrix : public std::runtime_error {
 public:
  /// @param x evaluation point, metres (reported in mm)
  /// @param num_nodes nodes in the local support
  /// @param rcond reciprocal condition number estimate of G (0 or NaN when the LU broke down; NaN when the rank
  ///        test refused the support before G was factorised)
  /// @param spread smallest eigenvalue of the support's coordinate covariance in units of d_c^2 (NaN: not reached)
  SingularRpimMatrix(const Eigen::Vector3d& x, int num_nodes, double rcond, double spread = std::nan(""));
  const Eigen::Vector3d& point() const { return point_; }
  int num_nodes() const { return num_nodes_; }
  double rcond() const { return rcond_; }
  double spread() const { return spread_; }

 private:
  Eigen::Vector3d point_;
  int num_nodes_;
  double rcond_;
  double spread_;
};

/// Shape parameters. Defaults are the literature's (docs/LRPIM.md §2): Liu & Gu (2001, 2005) recommend the
/// multiquadric with q = 1.03 and alpha_c = 4 (later work of theirs uses 1.0-4.0) and d_c the nodal spacing.
struct RpimParameters {
  int num_neighbours = 20;  ///< n, the nodes of each point's support (nearest n of the cloud)
  double q = 1.03;          ///< MQ exponent in R(r) = (r^2 + (alpha_c d_c)^2)^q
  double alpha_c = 4.0;     ///< MQ shape factor (dimensionless)
  /// G counts as singular below this reciprocal condition number (LU 1-norm estimate of G in units of d_c).
  /// The nearly flat MQ with q = 1.03, alpha_c = 4 gives rcond ~1e-9..1e-7 on a healthy cloud
  /// (tests/test_lrpim.cpp prints it); a coplanar support gives 0 or ~1e-17.
  double min_rcond = 1e-13;
  /// The rank test of P = [1 x y z] that the LU's rcond cannot replace (an exactly coplanar support left rcond at
  /// ~1e-8): the support counts as (nearly) coplanar when the smallest eigenvalue of its nodes' coordinate
  /// covariance, in units of d_c^2, is below this. P has full column rank exactly when that eigenvalue is > 0;
  /// 20 nodes of a healthy cloud give ~0.1 (tests/test_lrpim.cpp prints the smallest met).
  double min_spread = 1e-6;
};

/// phi(X) and grad phi(X) on the support of one point.
struct RpimEvaluation {
  std::vector<int> nodes;                         ///< #n node ids, nearest first
  Eigen::VectorXd phi;                            ///< #n, dimensionless
  Eigen::Matrix<double, 3, Eigen::Dynamic> dphi;  ///< 3 by #n [1/m]; 3 by 0 without gradients
  double rcond = 0.0;                             ///< diagnostic: rcond of G
  double spread = 0.0;                            ///< diagnostic: RpimParameters::min_spread's measure
  int size() const { return static_cast<int>(nodes.size()); }
};

/// RPIM with the augmented basis (Liu & Gu 2005, eq. 3.37-3.44):
///   u(X) = sum_i R_i(X) a_i + p(X)^T b,  with sum_i p(X_i) a_i = 0 (the constraint that makes G square),
///   G = [R0 P; P^T 0],  R0_ij = R(|X_i - X_j|),  P_i = p(X_i)^T,
///   [phi; psi] = G^-1 [R(X); p(X)]   (G is symmetric), grad phi from the same factors with [R_,k; p_,k].
/// The linear block reproduces linear fields exactly, so partition of unity and linear reproduction hold to the
/// round-off of G; interpolation (phi_i(X_j) = delta_ij) holds because [R(X_j); p(X_j)] is column j of G.
/// Distances are scaled by d_c and p is centred at X: R is then multiplied by the constant d_c^(-2q) and p by a
/// constant invertible matrix, which leaves phi unchanged but keeps G O(1).
/// The support is the n nearest nodes, so phi is discontinuous where the neighbour set changes (a known RPIM
/// property, Liu & Gu 2005 §3.3: the weak form only needs phi and its gradient at quadrature points).
/// Nodes and search are referenced and must outlive this object. evaluate() is const and thread-safe.
class RpimShapeFunctions {
 public:
  /// @param nodes #nodes by 3, metres
  /// @param search KD-tree on `nodes`
  /// @param spacing d_c, the nodal spacing [m] that scales the MQ shape parameter
  RpimShapeFunctions(const core::PointMatrix& nodes, const NodeSearch& search, double spacing,
                     RpimParameters parameters = {});

  /// @throws SingularRpimMatrix (see RpimParameters::min_rcond); std::invalid_argument for a non-finite x
  void evaluate(const Eigen::Vector3d& x, bool with_gradients, RpimEvaluation* out) const;
  RpimEvaluation evaluate(const Eigen::Vector3d& x, bool with_gradients) const;

  const RpimParameters& parameters() const { return parameters_; }
  double spacing() const { return spacing_; }
  /// d_c per node [m] (referenced, must outlive this object; empty: the constant spacing). d_c at a point is then
  /// the mean of its support nodes' spacings: Liu & Gu's "average nodal spacing near the point", which on a graded
  /// cloud keeps alpha_c d_c the same multiple of the local spacing everywhere.
  void set_node_spacing(const std::vector<double>* spacing) { node_spacing_ = spacing; }

 private:
  const core::PointMatrix* nodes_;
  const NodeSearch* search_;
  double spacing_;
  RpimParameters parameters_;
  const std::vector<double>* node_spacing_ = nullptr;
};

}  // namespace meshless::lrpim
