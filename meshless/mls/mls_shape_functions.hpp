#pragma once
// Moving-least-squares shape functions of the element-free Galerkin model (paper §2, eqs. 1-8).
#include <Eigen/Core>
#include <functional>
#include <stdexcept>
#include <utility>
#include <vector>

#include "core/tet_mesh.hpp"

namespace meshless {

class NodeSearch;
class SupportRadii;

/// Thrown when the moment matrix A(X) of eq. 3 cannot be inverted reliably at an evaluation point: fewer than
/// 4 nodes cover X, or the covering nodes are (nearly) coplanar so that the linear basis is not determined.
/// Callers see the point and the neighbour count instead of NaN shape functions.
class SingularMomentMatrix : public std::runtime_error {
 public:
  /// @param x evaluation point, metres (the message reports it in mm)
  /// @param num_covering nodes whose support sphere contains x
  /// @param num_weighted of those, the nodes left with a non-zero weight after the weight modifier
  /// @param rcond estimated reciprocal condition number of the scaled A(X); 0 if not factorised
  SingularMomentMatrix(const Eigen::Vector3d& x, int num_covering, int num_weighted, double rcond);
  const Eigen::Vector3d& point() const { return point_; }  ///< metres
  int num_covering() const { return num_covering_; }
  int num_weighted() const { return num_weighted_; }
  double rcond() const { return rcond_; }

 private:
  Eigen::Vector3d point_;
  int num_covering_;
  int num_weighted_;
  double rcond_;
};

/// Shape functions at one point: Phi(X) of eq. 6 restricted to the nodes whose weight is non-zero there.
struct MlsEvaluation {
  std::vector<int> nodes;                         ///< #n node ids, ascending
  Eigen::VectorXd phi;                            ///< #n, phi_i(X), dimensionless
  Eigen::Matrix<double, 3, Eigen::Dynamic> dphi;  ///< 3 by #n, d phi_i / d X [1/m]; 3 by 0 without gradients
  double rcond = 0.0;  ///< diagnostic: reciprocal condition number estimate of the scaled A(X)
  int size() const { return static_cast<int>(nodes.size()); }
};

/// Tuning of the singularity test.
struct MlsOptions {
  /// A(X) counts as singular below this reciprocal condition number (1-norm estimate of the moment matrix in
  /// the shifted, scaled basis, where a healthy cloud gives 1e-3..1e-1). 1e-10 still leaves ~6 correct
  /// digits.
  double min_rcond = 1e-10;
};

/// Optional per-node multiplier of the weight, h_i(X) in [0, 1] (paper §4: the enrichment/visibility function
/// of eqs. 29-32 multiplies w_i; meshless/cut/cut_weights.hpp). Called as modifier(node, X, side, grad): return h_i(X)
/// and, when grad is not null, write dh_i/dX [1/m] into *grad (grad is null when gradients are not requested, so
/// skip that work). `side` is the evaluation's side hint (see MlsShapeFunctions::evaluate): +1 or -1 for a point
/// that lies on a cut and is evaluated as the limit from that side, 0 otherwise. A C1 h_i >= 0 has zero gradient
/// where it vanishes, which is why nodes with h_i(X) = 0 can be dropped.
using WeightModifier = std::function<double(int node, const Eigen::Vector3d& x, int side, Eigen::Vector3d* grad)>;

/// MLS shape functions with the linear basis P = [1, x, y, z] (eq. 1) and the cubic spline weight (eq. 8):
///   A(X) = sum_i w_i(X) p(X_i) p(X_i)^T                  (eq. 3)
///   Phi_i(X) = p(X)^T A(X)^-1 w_i(X) p(X_i)               (eq. 6)
/// Derivatives follow Belytschko et al.'s EFG product rule, with gamma = A^-1 p(X):
///   gamma_,k = A^-1 (p_,k - A_,k gamma),  A_,k = sum_i w_i,k p_i p_i^T,
///   Phi_i,k = gamma_,k^T p_i w_i + gamma^T p_i w_i,k.
/// The basis is evaluated as p(Y) = [1, (Y - X)/h] with the centre X and scale h frozen per evaluation point
/// (h = largest support radius among the weighted nodes). A constant invertible change of basis leaves Phi
/// unchanged, so these are exactly the shape functions of eq. 6 and, differentiating with centre and scale
/// held fixed, exactly their gradients; but A is O(1) and well conditioned instead of mixing 1 with
/// coordinates of ~0.1 m, which is what makes partition of unity and linear reproduction hold to 1e-15..1e-13
/// (tests/test_mls_shape_functions.cpp).
///
/// The node matrix, radii and search are referenced and must outlive this object. evaluate() is const and
/// thread-safe as long as the weight modifier is.
class MlsShapeFunctions {
 public:
  /// @param nodes #nodes by 3, metres
  /// @param radii #nodes support radii rho_i [m]
  /// @param search KD-tree built on `nodes`
  MlsShapeFunctions(const core::PointMatrix& nodes, const SupportRadii& radii, const NodeSearch& search,
                    MlsOptions options = {});

  /// Shape functions (and gradients if asked) at X.
  /// @param x evaluation point, metres
  /// @param side handed to the weight modifier: +1 / -1 evaluates a point on a cut as the limit from that side
  ///        (a lip); 0 lets the modifier decide from x
  /// @throws SingularMomentMatrix if A(X) is singular or ill-conditioned (see MlsOptions)
  /// @throws std::invalid_argument if x is not finite; std::domain_error if the modifier leaves [0, 1]
  MlsEvaluation evaluate(const Eigen::Vector3d& x, bool with_gradients, int side = 0) const;

  /// Same, writing into `out` so that loops over quadrature points reuse its storage.
  void evaluate(const Eigen::Vector3d& x, bool with_gradients, MlsEvaluation* out, int side = 0) const;

  /// Install (or, with an empty function, remove) the weight multiplier h_i(X); see WeightModifier.
  void set_weight_modifier(WeightModifier modifier) { modifier_ = std::move(modifier); }
  bool has_weight_modifier() const { return static_cast<bool>(modifier_); }
  const WeightModifier& weight_modifier() const { return modifier_; }

  int num_nodes() const { return static_cast<int>(nodes_->rows()); }
  const MlsOptions& options() const { return options_; }

 private:
  const core::PointMatrix* nodes_;
  const SupportRadii* radii_;
  const NodeSearch* search_;
  MlsOptions options_;
  WeightModifier modifier_;
};

}  // namespace meshless
