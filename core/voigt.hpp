#pragma once
// Voigt notation shared by both models.
//
// Order follows the paper's operator L (eq. 17) and B matrix (eq. 22): [xx, yy, zz, xy, yz, zx].
// Strain vectors carry ENGINEERING shear strains (gamma_xy = 2 eps_xy), stress vectors carry the tensor
// components, so that  strain_vector . stress_vector  is the work density.
#include <Eigen/Core>

namespace core {

using Vector6 = Eigen::Matrix<double, 6, 1>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Matrix3 = Eigen::Matrix3d;

/// Symmetric strain tensor -> engineering Voigt vector.
inline Vector6 strain_to_voigt(const Matrix3& e) {
  Vector6 v;
  v << e(0, 0), e(1, 1), e(2, 2), 2.0 * e(0, 1), 2.0 * e(1, 2), 2.0 * e(2, 0);
  return v;
}

/// Engineering Voigt vector -> symmetric strain tensor.
inline Matrix3 voigt_to_strain(const Vector6& v) {
  Matrix3 e;
  e << v(0), 0.5 * v(3), 0.5 * v(5),  //
      0.5 * v(3), v(1), 0.5 * v(4),   //
      0.5 * v(5), 0.5 * v(4), v(2);
  return e;
}

/// Symmetric stress tensor -> Voigt vector (tensor components).
inline Vector6 stress_to_voigt(const Matrix3& s) {
  Vector6 v;
  v << s(0, 0), s(1, 1), s(2, 2), s(0, 1), s(1, 2), s(2, 0);
  return v;
}

/// Voigt stress vector -> symmetric stress tensor.
inline Matrix3 voigt_to_stress(const Vector6& v) {
  Matrix3 s;
  s << v(0), v(3), v(5),  //
      v(3), v(1), v(4),   //
      v(5), v(4), v(2);
  return s;
}

}  // namespace core
