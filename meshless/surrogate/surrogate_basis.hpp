#pragma once
// The spatial basis of the induced surface function (paper eq. 28) over surface-local coordinates.
//
// The paper writes the induced displacement of the other surface nodes as polynomials in x and y, assuming a
// flat surface (constant z). A lung is curved, so the coordinates here are those of the contact node's own
// frame (docs/SURROGATE.md §3): xi and eta along its tangent plane, zeta along its outward normal, all
// divided by the distance to the farthest surface node so that they lie in [-1, 1]. The basis has two parts:
//  * the paper's smooth surface function, generalised to a curved surface:
//        xi^p eta^q zeta^r,   p + q <= a (tangential order),  r <= b (normal order);
//    on a flat surface (zeta = 0) it is the paper's bivariate polynomial;
//  * contact terms of order c, which a low-order polynomial cannot follow: the dent under the probe decays
//  like
//    the point-force (Kelvin) solution u ~ (delta_ij + e_i e_j) / rho. With rho = sqrt(|x|^2 + l^2) (the
//    distance regularised over the patch, l = contact_length) and e = x / rho, s = l / rho:
//        s^m e^alpha,   m = 1..c,  alpha a monomial of degree <= 2 in (e_xi, e_eta, e_zeta)  (10 per m);
//    c = 0 gives the polynomial alone.
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
  double length = 1.0;                                ///< [m] divides every coordinate
  double contact_length = 0.0;                        ///< [m] l of the contact terms

  /// Frame at `origin` with outward `normal`; tangent1 is the global axis least aligned with the normal,
  /// projected onto the tangent plane (deterministic); `length` > 0, `contact_length` > 0.
  static SurfaceFrame at(const Eigen::Vector3d& origin, const Eigen::Vector3d& normal, double length,
                         double contact_length);
  /// (xi, eta, zeta) of x: (x - origin) in the frame, divided by length.
  Eigen::Vector3d local(const Eigen::Vector3d& x) const;
};

/// One basis function: a polynomial term (m = 0) xi^p eta^q zeta^r, or a contact term (m >= 1) s^m e^(p,q,r).
struct BasisTerm {
  int p = 0, q = 0, r = 0;
  int m = 0;
  bool operator==(const BasisTerm& o) const { return p == o.p && q == o.q && r == o.r && m == o.m; }
};

/// The terms of orders (a, b, c) in a fixed order: the polynomial terms by total tangential degree, then q,
/// then r; then the contact terms by m, then degree. The basis of orders (a', b', c') <= (a, b, c) is a
/// subset (subset()), in the same order, so one evaluation at the largest orders serves the whole
/// cross-validation grid.
class SpatialBasis {
 public:
  /// @param contact_length l / frame length (dimensionless), > 0 when contact_order > 0
  SpatialBasis(int tangential_order, int normal_order, int contact_order, double contact_length);
  int tangential_order() const { return a_; }
  int normal_order() const { return b_; }
  int contact_order() const { return c_; }
  int size() const { return static_cast<int>(terms_.size()); }
  const std::vector<BasisTerm>& terms() const { return terms_; }

  /// psi_k at local coordinates (xi, eta, zeta); `out` gets size() values.
  void evaluate(const Eigen::Vector3d& local, double* out) const { evaluate(local, local, out); }
  /// The same with the contact terms centred elsewhere: the polynomial terms at `local`, the contact terms at
  /// `contact_offset` = local(X) - local(contact point). The basis of a contact region (region_field.hpp) moves
  /// its contact terms with the probe while its polynomial stays in the region's frame.
  void evaluate(const Eigen::Vector3d& local, const Eigen::Vector3d& contact_offset, double* out) const;
  /// #points by size() matrix of psi_k at the given local coordinates (#points by 3).
  Eigen::MatrixXd evaluate(const Eigen::MatrixX3d& local) const;
  /// Column indices of the terms of orders (a', b', c') inside this basis.
  std::vector<int> subset(int tangential_order, int normal_order, int contact_order) const;

 private:
  int a_, b_, c_;
  double ell_;
  std::vector<BasisTerm> terms_;
};

}  // namespace meshless
