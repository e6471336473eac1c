#include "meshless/surrogate/contact_region.hpp"

#include <Eigen/Dense>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace meshless {
namespace {

/// The thin-plate spline's kernel r^2 log r (0 at r = 0): the 2-D biharmonic Green's function, so the
/// interpolant is the smoothest (least bending energy) surface through the values.
double thin_plate(double r) { return r > 0.0 ? r * r * std::log(r) : 0.0; }

/// Index of the untaken candidate farthest from every chosen node; -1 when none is left.
int farthest_from(const std::vector<char>& taken, const std::vector<double>& distance) {
  int best = -1;
  for (std::size_t k = 0; k < taken.size(); ++k)
    if (!taken[k] && (best < 0 || distance[k] > distance[best])) best = static_cast<int>(k);
  return best;
}

}  // namespace

RegionContacts select_region_contacts(const SurfaceNodes& surface, const Eigen::Vector3d& centre, double radius,
                                      int n_training, int n_holdout) {
  if (!(radius > 0.0) || n_training < 3 || n_holdout < 0)
    throw std::invalid_argument("select_region_contacts: expected radius > 0, >= 3 training contacts");
  RegionContacts out;
  out.centre_node = surface.nearest(centre, &out.centre_snap_distance);
  const Eigen::Vector3d c = surface.position.row(out.centre_node).transpose();
  std::vector<int> candidates;
  for (int s = 0; s < surface.size(); ++s)
    if ((surface.position.row(s).transpose() - c).norm() <= radius) candidates.push_back(s);
  out.region_nodes = static_cast<int>(candidates.size());
  if (out.region_nodes < n_training + n_holdout)
    throw std::invalid_argument(fmt::format(
        "the contact region of radius {:.4g} mm around ({:.4g}, {:.4g}, {:.4g}) mm holds {} surface nodes of the "
        "cloud, fewer than the {} training and {} held-out contacts asked for; enlarge "
        "/surrogate/contact_region/radius, lower training_contacts or holdout_contacts, or refine the cloud there",
        radius * 1e3, c.x() * 1e3, c.y() * 1e3, c.z() * 1e3, out.region_nodes, n_training, n_holdout));

  // Farthest-point sampling: each next contact is the region node farthest from all chosen so far, which
  // spreads the contacts over the region and puts them on its rim early (the interpolation needs its hull).
  std::vector<char> taken(candidates.size(), 0);
  std::vector<double> distance(candidates.size(), std::numeric_limits<double>::infinity());
  auto take = [&](int k, std::vector<int>* into) {
    taken[k] = 1;
    into->push_back(candidates[k]);
    const Eigen::Vector3d x = surface.position.row(candidates[k]).transpose();
    for (std::size_t m = 0; m < candidates.size(); ++m)
      distance[m] = std::min(distance[m], (surface.position.row(candidates[m]).transpose() - x).norm());
  };
  take(static_cast<int>(std::find(candidates.begin(), candidates.end(), out.centre_node) - candidates.begin()),
       &out.training);
  while (static_cast<int>(out.training.size()) < n_training)
    take(farthest_from(taken, distance), &out.training);
  // Held-out nodes: the distances stay those to the TRAINED nodes (a held-out node does not inform the next).
  std::vector<double> to_trained = distance;
  while (static_cast<int>(out.holdout.size()) < n_holdout) {
    const int k = farthest_from(taken, to_trained);
    taken[k] = 1;
    out.holdout.push_back(candidates[k]);
  }
  return out;
}

ContactInterpolation::ContactInterpolation(const ContactRegion& region, const std::vector<Eigen::Vector3d>& contacts) {
  const int n = static_cast<int>(contacts.size());
  if (n < 3) throw std::invalid_argument("ContactInterpolation: expected at least 3 trained contacts");
  if (!(region.radius > 0.0) || !(region.normal.norm() > 0.0))
    throw std::invalid_argument("ContactInterpolation: expected a region radius > 0 and a normal");
  const Eigen::Vector3d normal = region.normal.normalized();
  Eigen::Index axis = 0;
  normal.cwiseAbs().minCoeff(&axis);
  const Eigen::Vector3d e = Eigen::Vector3d::Unit(axis);
  origin_ = region.centre;
  axis1_ = (e - e.dot(normal) * normal).normalized();
  axis2_ = normal.cross(axis1_);
  scale_ = 1.0 / region.radius;  // coordinates of order 1: the system's conditioning does not depend on units

  plane_.resize(n, 2);
  for (int c = 0; c < n; ++c) plane_.row(c) = in_plane(contacts[c]).transpose();
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n + 3, n + 3);
  for (int c = 0; c < n; ++c) {
    for (int d = 0; d < n; ++d) a(c, d) = thin_plate((plane_.row(c) - plane_.row(d)).norm());
    a(c, n) = a(n, c) = 1.0;
    a(c, n + 1) = a(n + 1, c) = plane_(c, 0);
    a(c, n + 2) = a(n + 2, c) = plane_(c, 1);
  }
  // The TPS system is nonsingular exactly when the points are not all on one line (they determine the linear
  // part); check that through the linear block's rank rather than trusting the inverse.
  Eigen::MatrixXd linear(n, 3);
  linear << Eigen::VectorXd::Ones(n), plane_;
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(linear);
  qr.setThreshold(1e-6);
  if (qr.rank() < 3)
    throw std::invalid_argument(
        "ContactInterpolation: the trained contacts lie on one line in the region's plane; a contact region "
        "needs contacts spread over a surface patch (raise training_contacts or the radius)");
  cardinal_ = a.fullPivLu().inverse().topRows(n);
}

Eigen::Vector2d ContactInterpolation::in_plane(const Eigen::Vector3d& x) const {
  const Eigen::Vector3d d = (x - origin_) * scale_;
  return {d.dot(axis1_), d.dot(axis2_)};
}

void ContactInterpolation::weights(const Eigen::Vector3d& x, double* out) const {
  const int n = size();
  const Eigen::Vector2d t = in_plane(x);
  // w = (A^-1)[0:N, :] psi(t), psi = [phi(|t - t_c|)..., 1, t_x, t_y]; no temporary vector.
  for (int c = 0; c < n; ++c) {
    double w = cardinal_(c, n) + cardinal_(c, n + 1) * t.x() + cardinal_(c, n + 2) * t.y();
    for (int d = 0; d < n; ++d) w += cardinal_(c, d) * thin_plate((plane_.row(d).transpose() - t).norm());
    out[c] = w;
  }
}

}  // namespace meshless
