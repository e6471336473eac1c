#pragma once
// The spatial basis of the induced surface function (paper eq. 28) over surface-local coordinates.
//
// The paper writes the induced displacement of the other surface nodes as polynomials in x and y, assuming a flat
// surface (constant z). A lung is curved, so the coordinates here are those of the contact node's own frame
// (docs/SURROGATE.md §3): xi and eta along its tangent plane, zeta along its outward normal, all divided by the
// distance to the farthest surface node so that they lie in [-1, 1]. The basis is
//     psi(xi, eta, zeta) = xi^p eta^q zeta^r,   p + q <= a (tangential order),  r <= b (normal order),
// which is the paper's bivariate surface function when the surface is the tangent plane (b = 0 suffices there)
// and lets the fit follow the surface as it curves away from the tangent plane (b > 0).
#include <Eigen/Core>
#include <array>
#include <vector>

namespace meshless {

/// The contact node's frame: origin, orthonormal tangents and normal, and the length that scales coordinates.
struct SurfaceFrame {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< [m]
  Eigen::Vector3d tangent1 = Eigen::Vector3d::UnitX();
  Eigen::Vector3d tangent2 = Eigen::Vector3d::UnitY();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< outward
  double length = 1.0;                                ///< [m]

  /// Frame at `origin` with outward `normal`; tangent1 is the global axis least aligned with the normal, projected
  /// onto the tangent plane (deterministic); `length` > 0.
  static SurfaceFrame at(const Eigen::Vector3d& origin, const Eigen::Vector3d& normal, double length);
  /// (xi, eta, zeta) of x: (x - origin) in the frame, divided by length.
  Eigen::Vector3d local(const Eigen::Vector3d& x) const;
};

/// The monomials of orders (a, b) in a fixed order: by total tangential degree, then q, then r. The basis of
/// orders (a', b') with a' <= a and b' <= b is a subset (subset()), so one evaluation at the largest orders serves
/// the whole cross-validation grid.
class SpatialBasis {
 public:
  SpatialBasis(int tangential_order, int normal_order);
  int tangential_order() const { return a_; }
  int normal_order() const { return b_; }
  int size() const { return static_cast<int>(exponents_.size()); }
  const std::vector<std::array<int, 3>>& exponents() const { return exponents_; }  ///< (p, q, r) per function

  /// psi_k at local coordinates (xi, eta, zeta); `out` gets size() values.
  void evaluate(const Eigen::Vector3d& local, double* out) const;
  /// #points by size() matrix of psi_k at the given local coordinates (#points by 3).
  Eigen::MatrixXd evaluate(const Eigen::MatrixX3d& local) const;
  /// Column indices of the functions of orders (a', b') inside this basis.
  std::vector<int> subset(int tangential_order, int normal_order) const;

 private:
  int a_, b_;
  std::vector<std::array<int, 3>> exponents_;
};

}  // namespace meshless
