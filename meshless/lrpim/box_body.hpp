#pragma once
// An axis-aligned box with its analytic ray exit distance: the verification problems' body, which the model takes as
// its 12 triangles (SurfaceBody::from_box, labels = the face indices below), and the reference the surface body's
// rays are tested against (tests/test_lrpim.cpp, docs/LRPIM.md §3). Units: metres.
#include <Eigen/Core>
#include <algorithm>
#include <limits>

namespace meshless::lrpim {

/// Faces in the order -x, +x, -y, +y, -z, +z: face f has axis f / 2 and outward sign (f % 2 ? +1 : -1).
constexpr int kBoxFaces = 6;

struct BoxBody {
  Eigen::Vector3d lo = Eigen::Vector3d::Zero();  ///< [m]
  Eigen::Vector3d hi = Eigen::Vector3d::Ones();  ///< [m]

  /// Distance from x (inside or on the box) along the unit direction d to the box's boundary; 0 when d leaves
  /// through a face x lies on.
  double exit_distance(const Eigen::Vector3d& x, const Eigen::Vector3d& d) const {
    double t = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
      if (d[k] > 0.0) t = std::min(t, (hi[k] - x[k]) / d[k]);
      if (d[k] < 0.0) t = std::min(t, (lo[k] - x[k]) / d[k]);
    }
    return std::max(t, 0.0);
  }
};

}  // namespace meshless::lrpim
