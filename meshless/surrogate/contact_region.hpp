#pragma once
// A contact region of the surrogate (docs/SURROGATE.md §4, "A contact region"): a patch of the surface that a
// haptic probe may touch anywhere, covered by a few trained contact nodes. This file chooses those nodes and
// interpolates the contact node's own response (eqs. 25-27) between them; the surface's response (eq. 28) over
// the region is one fit with the contact position as a variable (region_field.hpp).
//
// The interpolation weights w_c(p) are the cardinal functions of a thin-plate spline with a linear polynomial in
// the region's tangent plane: they interpolate (w_c(p_d) = delta_cd, so a query at a trained contact returns that
// contact's eqs. 25-27 exactly), sum to one and reproduce linear functions of the position.
//
// Units: SI (m). Lifetime and threads: ContactInterpolation is immutable after construction; weights() is
// const, allocates nothing and may run from several threads at once.
#include <Eigen/Core>
#include <vector>

#include "meshless/surrogate/surrogate_load_patch.hpp"

namespace meshless {

/// What a region is, as the surrogate file keeps it.
struct ContactRegion {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  ///< [m] the centre node
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< outward unit normal at the centre: the region's plane
  double radius = 0.0;                                ///< [m] straight-line distance from the centre
  bool contains(const Eigen::Vector3d& x) const { return (x - centre).norm() <= radius * (1.0 + 1e-12); }
};

/// The surface nodes of a region, split into trained and held-out contacts.
struct RegionContacts {
  int centre_node = -1;            ///< index into SurfaceNodes
  std::vector<int> training;       ///< the centre node first, then by farthest-point sampling
  std::vector<int> holdout;        ///< untrained region nodes, farthest from the trained ones first
  int region_nodes = 0;            ///< surface nodes inside the region
  double centre_snap_distance = 0.0;  ///< [m] from the configured centre to the centre node
};

/// Choose `n_training` well-spread contacts among the surface nodes within `radius` of the node nearest
/// `centre` (the centre node first, then each next node the farthest from those chosen), then `n_holdout`
/// untrained nodes the same way (the farthest from every trained one: where the interpolation is weakest).
/// Throws std::invalid_argument saying how many nodes the region holds and what to change when it holds fewer
/// than n_training + n_holdout.
RegionContacts select_region_contacts(const SurfaceNodes& surface, const Eigen::Vector3d& centre, double radius,
                                      int n_training, int n_holdout);

/// Cardinal thin-plate-spline weights over the trained contacts, in the region's tangent plane.
class ContactInterpolation {
 public:
  /// @param region   its centre and normal define the plane; its radius scales the coordinates
  /// @param contacts trained contact positions [m], at least 3, not all on one line
  /// Throws std::invalid_argument when the points do not determine a plane's linear function.
  ContactInterpolation(const ContactRegion& region, const std::vector<Eigen::Vector3d>& contacts);

  int size() const { return static_cast<int>(plane_.rows()); }
  /// w_c(x) for every trained contact, into `out` (size() values): sum w_c = 1, sum w_c p_c = p for the
  /// in-plane part of p, and w_c(p_d) = delta_cd.
  void weights(const Eigen::Vector3d& x, double* out) const;

 private:
  Eigen::Vector2d in_plane(const Eigen::Vector3d& x) const;
  Eigen::Vector3d origin_, axis1_, axis2_;
  double scale_ = 1.0;
  Eigen::Matrix<double, Eigen::Dynamic, 2> plane_;  ///< contacts in plane coordinates (scaled)
  Eigen::MatrixXd cardinal_;  ///< first N rows of the inverse of the TPS system [N + 3 columns]
};

}  // namespace meshless
