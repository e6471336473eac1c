#pragma once
// The Timoshenko & Goodier cantilever: the closed form against which every model's cantilever verification is
// measured (the FEM's, the EFG's and the LRPIM's). Origin at the clamped end x = 0, y about the neutral axis, z across
// the width; plane stress, which with nu = 0 is an exact 3-D elasticity solution. Units: SI (m, N, Pa).
#include <Eigen/Core>

#include "core/voigt.hpp"

namespace core {

struct TimoshenkoCantilever {
  double P = 0.0;   ///< end shear [N], along +y at x = L
  double E = 0.0;   ///< Young's modulus [Pa]
  double nu = 0.0;  ///< Poisson's ratio (0 for an exact 3-D solution)
  double L = 0.0;   ///< length [m]
  double D = 0.0;   ///< depth along y [m]
  double I = 0.0;   ///< second moment of the section, B D^3 / 12 [m^4]

  Eigen::Vector3d displacement(const Eigen::Vector3d& x) const {
    const double X = x.x(), Y = x.y();
    return {-P * Y / (6 * E * I) * ((6 * L - 3 * X) * X + (2 + nu) * (Y * Y - D * D / 4)),
            P / (6 * E * I) * (3 * nu * Y * Y * (L - X) + (4 + 5 * nu) * D * D * X / 4 + (3 * L - X) * X * X), 0.0};
  }
  /// Engineering Voigt strain (xx, yy, zz, gamma_xy, gamma_yz, gamma_zx).
  Vector6 strain(const Eigen::Vector3d& x) const {
    const double X = x.x(), Y = x.y();
    Vector6 e = Vector6::Zero();
    e[0] = -P * (L - X) * Y / (E * I);
    e[1] = -nu * e[0];
    e[2] = -nu * e[0];
    e[3] = P * (1 + nu) / (E * I) * (D * D / 4 - Y * Y);
    return e;
  }
  /// The traction sigma . e_x on the loaded end x = L: the parabolic shear whose resultant is P.
  Eigen::Vector3d end_traction(const Eigen::Vector3d& x) const {
    return {0.0, P / (2 * I) * (D * D / 4 - x.y() * x.y()), 0.0};
  }
};

}  // namespace core
