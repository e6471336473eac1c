#pragma once
// The body of the first LRPIM version: an axis-aligned box. The local sub-domains of the MLPG weak form are
// clipped by it along rays from the node (meshless/lrpim/local_quadrature.hpp), which needs only "how far from X
// along a direction does the body go" and the planar faces. A general (star-shaped about each node) body would
// answer the same two questions from its surface (core::TriangleSurface ray casting); docs/LRPIM.md §3.
#include <Eigen/Core>
#include <algorithm>
#include <limits>

namespace meshless::lrpim {

/// Faces in the order -x, +x, -y, +y, -z, +z: face f has axis f / 2 and outward sign (f % 2 ? +1 : -1).
constexpr int kBoxFaces = 6;

struct BoxBody {
  Eigen::Vector3d lo = Eigen::Vector3d::Zero();  ///< [m]
  Eigen::Vector3d hi = Eigen::Vector3d::Ones();  ///< [m]

  static int axis(int face) { return face / 2; }
  static double sign(int face) { return face % 2 ? 1.0 : -1.0; }
  double plane(int face) const { return face % 2 ? hi[axis(face)] : lo[axis(face)]; }
  Eigen::Vector3d normal(int face) const { return sign(face) * Eigen::Vector3d::Unit(axis(face)); }

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

  /// Same within the plane of `face`: from x on that plane along an in-plane unit direction d.
  double exit_distance_in_face(int face, const Eigen::Vector3d& x, const Eigen::Vector3d& d) const {
    double t = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
      if (k == axis(face)) continue;
      if (d[k] > 0.0) t = std::min(t, (hi[k] - x[k]) / d[k]);
      if (d[k] < 0.0) t = std::min(t, (lo[k] - x[k]) / d[k]);
    }
    return std::max(t, 0.0);
  }

  /// Whether x lies on the face (its plane, within the face) to tol [m].
  bool on_face(int face, const Eigen::Vector3d& x, double tol) const {
    if (std::abs(x[axis(face)] - plane(face)) > tol) return false;
    for (int k = 0; k < 3; ++k)
      if (k != axis(face) && (x[k] < lo[k] - tol || x[k] > hi[k] + tol)) return false;
    return true;
  }
};

}  // namespace meshless::lrpim
