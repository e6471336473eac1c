#pragma once
// The linear displacement field of the patch tests (the EFG's and the LRPIM's): u = a0 + G x, with its constant
// engineering strain and, for a given elastic law, its constant stress. A model that reproduces it to round-off passes
// the linear patch test. Units: SI.
#include <Eigen/Core>

#include "core/kelvin_law.hpp"
#include "core/voigt.hpp"

namespace meshless {

struct LinearPatchField {
  Eigen::Vector3d a0{1e-4, -2e-4, 3e-4};  ///< [m]
  Eigen::Matrix3d G = (Eigen::Matrix3d() << 1e-3, 2e-4, -3e-4,  //
                       -1e-4, -2e-3, 5e-4,                         //
                       4e-4, 1e-4, 1.5e-3)
                          .finished();

  Eigen::Vector3d displacement(const Eigen::Vector3d& x) const { return a0 + G * x; }
  /// Engineering Voigt strain (xx, yy, zz, gamma_xy, gamma_yz, gamma_zx), the same everywhere.
  core::Vector6 strain() const {
    return {G(0, 0), G(1, 1), G(2, 2), G(0, 1) + G(1, 0), G(1, 2) + G(2, 1), G(2, 0) + G(0, 2)};
  }
  /// The constant stress of `law`'s instantaneous (K1) elastic response to strain() [Pa].
  core::Matrix3 stress(const core::KelvinLaw& law) const {
    return core::voigt_to_stress(law.elastic_matrix(law.parameters().K1) * strain());
  }
};

}  // namespace meshless
