#include "meshless/surrogate/surrogate.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace meshless {
namespace {
constexpr int kMaxOrder = 8;  // largest force order a surrogate may hold (SurrogateFitOptions::IsValid)
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

  // Trained range: clamp and flag, never extrapolate the polynomials.
  const double f_max = data_.max_force;
  for (int j = 0; j < 3; ++j) {
    r.force[j] = std::clamp(force[j], -f_max, f_max);
    if (!(std::abs(force[j]) <= f_max * (1.0 + 1e-12))) r.force_in_range = false;
  }

  // Powers sigma_j^p, p = 1..8.
  double power[3][kMaxOrder];
  for (int j = 0; j < 3; ++j) {
    power[j][0] = r.force[j];
    for (int p = 1; p < kMaxOrder; ++p) power[j][p] = power[j][p - 1] * r.force[j];
  }
  // Eqs. 25-27 at the contact node, the three axes superposed.
  for (int j = 0; j < 3; ++j) {
    const AxisFit& a = fit.axis[j];
    r.contact_displacement.noalias() +=
        a.contact * Eigen::Map<const Eigen::VectorXd>(power[j], a.force_order);
  }
  // The powers of eq. 28 in the column order of nodal_ (field orders of x, then y, then z).
  double field_powers[3 * kMaxOrder];
  int n = 0;
  for (int j = 0; j < 3; ++j)
    for (int p = 0; p < fit.axis[j].field_order; ++p) field_powers[n++] = power[j][p];
  const Eigen::Map<const Eigen::VectorXd> sigma(field_powers, n);

  // Eq. 28 at every surface node: one matrix-vector product.
  const int ns = num_surface_nodes();
  if (surface->rows() != ns) surface->resize(ns, 3);
  Eigen::Map<Eigen::VectorXd> u(surface->data(), 3 * ns);  // row-major #S by 3: node s, component i at 3s + i
  u.noalias() = nodal_[r.contact] * sigma;
  surface->row(r.contact_node) = r.contact_displacement.transpose();  // the stressed node follows eqs. 25-27
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

}  // namespace meshless
