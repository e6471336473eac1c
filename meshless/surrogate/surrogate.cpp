#include "meshless/surrogate/surrogate.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace meshless {
namespace {
constexpr int kMaxOrder = 8;  // largest force order a surrogate may hold (SurrogateFitOptions::IsValid)
constexpr int kMaxRegionContacts = 64;  // core::ContactRegionSpec::training_contacts is at most 64
/// The force powers of one contact: adds `weight` times its eqs. 25-27 (the three axes superposed) to
/// `contact_displacement`, and writes sigma_j^p in the column order of nodal_ into `field_powers` (3 * kMaxOrder).
Eigen::Map<const Eigen::VectorXd> contact_response_and_powers(const ContactFit& fit, const Eigen::Vector3d& force,
                                               Eigen::Vector3d* contact_displacement, double* field_powers,
                                               double weight = 1.0) {
  double power[3][kMaxOrder];  // sigma_j^p, p = 1..8
  for (int j = 0; j < 3; ++j) {
    power[j][0] = force[j];
    for (int p = 1; p < kMaxOrder; ++p) power[j][p] = power[j][p - 1] * force[j];
  }
  for (int j = 0; j < 3; ++j) {
    const AxisFit& a = fit.axis[j];
    contact_displacement->noalias() += weight * (a.contact * Eigen::Map<const Eigen::VectorXd>(power[j], a.force_order));
  }
  int n = 0;
  for (int j = 0; j < 3; ++j)
    for (int p = 0; p < fit.axis[j].field_order; ++p) field_powers[n++] = power[j][p];
  return Eigen::Map<const Eigen::VectorXd>(field_powers, n);
}

}  // namespace

Surrogate::Surrogate(SurrogateData data, double contact_tolerance) : data_(std::move(data)) {
  tolerance_ = contact_tolerance > 0.0 ? contact_tolerance : data_.patch_radius;
  if (!(data_.max_force > 0.0)) throw std::invalid_argument("Surrogate: max_force must be > 0");
  if (data_.contacts.empty()) throw std::invalid_argument("Surrogate: no trained contact node");
  SurfaceNodes surface;  // the positions are all eq. 28 needs
  surface.position = data_.surface_position;
  surface.vertex = data_.surface_vertex;
  for (const ContactFit& c : data_.contacts) {
    if (c.contact < 0 || c.contact >= num_surface_nodes())
      throw std::invalid_argument("Surrogate: a contact node is not a surface node");
    int columns = 0;
    for (const AxisFit& a : c.axis) {
      if (a.force_order < 1 || a.force_order > kMaxOrder || a.contact.cols() != a.force_order)
        throw std::invalid_argument("Surrogate: eqs. 25-27 coefficients do not match lambda");
      if (a.field_order < 1 || a.field_order > kMaxOrder)
        throw std::invalid_argument("Surrogate: eq. 28 force order outside [1, 8]");
      columns += a.field_order;
    }
    Eigen::MatrixXd m(3 * num_surface_nodes(), columns);
    int col = 0;
    for (const AxisFit& a : c.axis) {
      m.middleCols(col, a.field_order) = nodal_coefficients(surface, c.frame, a);
      col += a.field_order;
    }
    nodal_.push_back(std::move(m));
  }
  if (!data_.region) return;

  // The contact region: eqs. 25-27 interpolated between the trained contacts, eq. 28 from the region's field.
  if (num_contacts() < 3 || num_contacts() > kMaxRegionContacts)
    throw std::invalid_argument("Surrogate: a contact region needs 3 to 64 trained contacts");
  if (!data_.region_field) throw std::invalid_argument("Surrogate: a contact region without its field");
  std::vector<Eigen::Vector3d> positions;
  for (const ContactFit& c : data_.contacts) positions.push_back(data_.surface_position.row(c.contact).transpose());
  interpolation_.emplace(*data_.region, positions);
  region_field_.emplace(*data_.region_field, data_.surface_position);
  // The correction of each trained contact: its own fit minus the region's field there, both as per-node force
  // polynomials in the region's column layout (a contact's own lambda' is at most the region's).
  for (int c = 0; c < num_contacts(); ++c) {
    Eigen::MatrixXd own = Eigen::MatrixXd::Zero(3 * num_surface_nodes(), region_field_->force_columns());
    int from = 0, to = 0;
    for (int j = 0; j < 3; ++j) {
      const int order = data_.contacts[c].axis[j].field_order;
      if (order > data_.region_field->axis[j].field_order)
        throw std::invalid_argument("Surrogate: a contact's field order exceeds its region's");
      own.middleCols(to, order) = nodal_[c].middleCols(from, order);
      from += order;
      to += data_.region_field->axis[j].field_order;
    }
    correction_.push_back(own - region_field_->nodal_at(positions[c]));
  }
}

SurrogateResponse Surrogate::query(const Eigen::Vector3d& point, const Eigen::Vector3d& force,
                                   core::PointMatrix* surface) const {
  SurrogateResponse r;
  // Nearest trained contact node (a handful: a linear scan).
  double best = std::numeric_limits<double>::infinity();
  for (int c = 0; c < num_contacts(); ++c) {
    const double d =
        (data_.surface_position.row(data_.contacts[c].contact).transpose() - point).squaredNorm();
    if (d < best) {
      best = d;
      r.contact = c;
    }
  }
  const ContactFit& fit = data_.contacts[r.contact];
  r.contact_node = fit.contact;
  r.contact_distance = std::sqrt(best);
  r.on_trained_contact = r.contact_distance <= tolerance_;
  r.in_contact_region = interpolation_.has_value() && data_.region->contains(point);

  // Trained range: clamp and flag, never extrapolate the polynomials.
  const double f_max = data_.max_force;
  for (int j = 0; j < 3; ++j) {
    r.force[j] = std::clamp(force[j], -f_max, f_max);
    if (!(std::abs(force[j]) <= f_max * (1.0 + 1e-12))) r.force_in_range = false;
  }

  const int ns = num_surface_nodes();
  if (surface->rows() != ns) surface->resize(ns, 3);
  if (r.in_contact_region) {
    interpolate_in_region(point, &r, surface);
  } else {
    // Eqs. 25-27 at the contact node, the three axes superposed; eq. 28 at every surface node: one
    // matrix-vector product.
    double field_powers[3 * kMaxOrder];
    const Eigen::Map<const Eigen::VectorXd> sigma = contact_response_and_powers(fit, r.force, &r.contact_displacement, field_powers);
    Eigen::Map<Eigen::VectorXd> u(surface->data(), 3 * ns);  // row-major #S by 3: node s, component i at 3s + i
    u.noalias() = nodal_[r.contact] * sigma;
    surface->row(r.contact_node) = r.contact_displacement.transpose();  // the stressed node follows eqs. 25-27
  }
  double largest = -1.0;
  for (int s = 0; s < ns; ++s) {
    const double m = surface->row(s).squaredNorm();
    if (m > largest) {
      largest = m;
      r.max_surface_node = s;
    }
  }
  r.max_surface_displacement = std::sqrt(largest);
  return r;
}

void Surrogate::interpolate_in_region(const Eigen::Vector3d& point, SurrogateResponse* r,
                                      core::PointMatrix* surface) const {
  const int nc = num_contacts(), ns = num_surface_nodes();
  double weight[kMaxRegionContacts];
  interpolation_->weights(point, weight);
  r->contact_displacement.setZero();
  for (int c = 0; c < nc; ++c) {
    double field_powers[3 * kMaxOrder];
    contact_response_and_powers(data_.contacts[c], r->force, &r->contact_displacement, field_powers, weight[c]);
  }
  // Eq. 28: the region's field at the probe, plus the trained contacts' corrections interpolated in place (so a
  // query at a trained contact is that contact's own fit; between contacts the corrections are the region fit's
  // smooth misfit, blended).
  Eigen::Map<Eigen::VectorXd> u(surface->data(), 3 * ns);  // row-major #S by 3
  region_field_->evaluate(point, r->force, u.data());
  double powers[3 * kMaxOrder];
  int n = 0;
  for (int j = 0; j < 3; ++j) {
    double power = 1.0;
    for (int p = 0; p < data_.region_field->axis[j].field_order; ++p) powers[n++] = power *= r->force[j];
  }
  const Eigen::Map<const Eigen::VectorXd> sigma(powers, n);
  for (int c = 0; c < nc; ++c)
    if (weight[c] != 0.0) u.noalias() += weight[c] * (correction_[c] * sigma);

  double nearest = std::numeric_limits<double>::infinity();
  for (int s = 0; s < ns; ++s) {
    const double d2 = (data_.surface_position.row(s).transpose() - point).squaredNorm();
    if (d2 < nearest) {
      nearest = d2;
      r->contact_node = s;
    }
  }
  r->contact_distance = std::sqrt(nearest);
  r->on_trained_contact = true;
  // A query AT a surface node: that node is the stressed one and follows eqs. 25-27 (interpolated), as the
  // trained contact node does outside the region. Between nodes no node carries the probe.
  if (r->contact_distance <= 1e-9 * data_.region->radius)
    surface->row(r->contact_node) = r->contact_displacement.transpose();
}

}  // namespace meshless
