#include "meshless/surrogate/surrogate.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace meshless {
namespace {
constexpr int kMaxOrder = 8;  // largest force order a surrogate may hold (SurrogateFitOptions::IsValid)
constexpr int kMaxRegionContacts = 64;  // core::ContactRegionSpec::training_contacts is at most 64
constexpr int kMaxDentOrder = 6;        // the file reader's largest contact order c
/// The degree <= 2 monomials of a direction e, in the order of the rows of dent_:
/// 1, e0, e1, e2, e0^2, e0 e1, e0 e2, e1^2, e1 e2, e2^2.
constexpr int kDirectionMonomials = 10;

/// Column layout of nodal_: the force powers of x (field order), then of y, then of z.
int field_columns(const ContactFit& c) {
  int columns = 0;
  for (const AxisFit& a : c.axis) columns += a.field_order;
  return columns;
}

/// The monomial rows (into the 10 above) and weights of e_f^(p,q,r), a monomial of degree <= 2 of the direction in
/// a frame f whose rows of `rotation` are its axes (e_f = R e), written in the global direction e.
Eigen::Matrix<double, kDirectionMonomials, 1> global_monomial(const Eigen::Matrix3d& rotation, int p, int q, int r) {
  Eigen::Matrix<double, kDirectionMonomials, 1> out = Eigen::Matrix<double, kDirectionMonomials, 1>::Zero();
  int axes[2], n = 0;
  for (int k = 0; k < p; ++k) axes[n++] = 0;
  for (int k = 0; k < q; ++k) axes[n++] = 1;
  for (int k = 0; k < r; ++k) axes[n++] = 2;
  if (n == 0) {
    out(0) = 1.0;
  } else if (n == 1) {
    out.segment<3>(1) = rotation.row(axes[0]).transpose();
  } else {
    // e_f[a] e_f[b] = sum_uv R(a,u) R(b,v) e_u e_v; the monomial e_u e_v (u < v) collects both orders.
    const int index[3][3] = {{4, 5, 6}, {5, 7, 8}, {6, 8, 9}};
    for (int u = 0; u < 3; ++u)
      for (int v = 0; v < 3; ++v) out(index[u][v]) += rotation(axes[0], u) * rotation(axes[1], v);
  }
  return out;
}

/// The force powers of one contact: adds `weight` times its eqs. 25-27 (the three axes superposed) to
/// `contact_displacement`, and writes sigma_j^p in the column order of nodal_ into `field_powers` (3 * kMaxOrder).
Eigen::Map<const Eigen::VectorXd> force_powers(const ContactFit& fit, const Eigen::Vector3d& force,
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

  // The contact region: split each contact's eq. 28 into its smooth part (evaluated at the nodes once, like
  // nodal_) and its contact terms (re-expressed in the global direction, so that they can be blended between
  // contacts and evaluated at X - p for any query point p).
  if (num_contacts() < 3 || num_contacts() > kMaxRegionContacts)
    throw std::invalid_argument("Surrogate: a contact region needs 3 to 64 trained contacts");
  std::vector<Eigen::Vector3d> positions;
  contact_length_ = data_.contacts.front().frame.contact_length;
  for (const ContactFit& c : data_.contacts) {
    positions.push_back(data_.surface_position.row(c.contact).transpose());
    if (std::abs(c.frame.contact_length - contact_length_) > 1e-12 * contact_length_)
      throw std::invalid_argument("Surrogate: the contacts of a region must share one contact length");
    for (const AxisFit& a : c.axis)
      for (const InducedFieldFit& f : a.field) dent_order_ = std::max(dent_order_, f.contact_order);
  }
  if (dent_order_ > kMaxDentOrder) throw std::invalid_argument("Surrogate: contact order above 6");
  interpolation_.emplace(*data_.region, positions);
  for (const ContactFit& c : data_.contacts) {
    Eigen::Matrix3d rotation;
    rotation << c.frame.tangent1.transpose(), c.frame.tangent2.transpose(), c.frame.normal.transpose();
    Eigen::MatrixXd smooth(3 * num_surface_nodes(), field_columns(c));
    Eigen::MatrixXd dent = Eigen::MatrixXd::Zero(3 * std::max(dent_order_, 1) * kDirectionMonomials, smooth.cols());
    int col = 0;
    for (const AxisFit& a : c.axis) {
      AxisFit polynomial = a;  // the same fit with its contact terms' coefficients set to zero
      for (int i = 0; i < 3; ++i) {
        const InducedFieldFit& f = a.field[i];
        const SpatialBasis basis(f.tangential_order, f.normal_order, f.contact_order,
                                 c.frame.contact_length / c.frame.length);
        for (int k = 0; k < basis.size(); ++k) {
          const BasisTerm& t = basis.terms()[k];
          if (t.m == 0) continue;
          polynomial.field[i].coefficients.row(k).setZero();
          const auto monomial = global_monomial(rotation, t.p, t.q, t.r);
          const int row = (i * dent_order_ + t.m - 1) * kDirectionMonomials;
          for (int p = 0; p < a.field_order; ++p)
            dent.block(row, col + p, kDirectionMonomials, 1) += f.coefficients(k, p) * monomial;
        }
      }
      smooth.middleCols(col, a.field_order) = nodal_coefficients(surface, c.frame, polynomial);
      col += a.field_order;
    }
    smooth_.push_back(std::move(smooth));
    dent_.push_back(std::move(dent));
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
    const Eigen::Map<const Eigen::VectorXd> sigma = force_powers(fit, r.force, &r.contact_displacement, field_powers);
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

  // The stressed point (eqs. 25-27) and the smooth part of eq. 28, interpolated; the contact terms' coefficients,
  // interpolated in the global direction monomials.
  constexpr int kDentRows = 3 * kMaxDentOrder * kDirectionMonomials;
  double dent_storage[kDentRows];
  const int dent_rows = static_cast<int>(dent_.front().rows());
  Eigen::Map<Eigen::VectorXd> dent(dent_storage, dent_rows);
  dent.setZero();
  Eigen::Map<Eigen::VectorXd> u(surface->data(), 3 * ns);
  u.setZero();
  r->contact_displacement.setZero();
  for (int c = 0; c < nc; ++c) {
    if (weight[c] == 0.0) continue;
    double field_powers[3 * kMaxOrder];
    const Eigen::Map<const Eigen::VectorXd> sigma =
        force_powers(data_.contacts[c], r->force, &r->contact_displacement, field_powers, weight[c]);
    u.noalias() += weight[c] * (smooth_[c] * sigma);
    dent.noalias() += weight[c] * (dent_[c] * sigma);
  }

  // The contact terms transported to the query point: s^m e^alpha with e = (X - p) / rho, s = l / rho,
  // rho = sqrt(|X - p|^2 + l^2) (surrogate_basis.hpp; these are independent of the frame's length scale).
  const double l2 = contact_length_ * contact_length_;
  double nearest = std::numeric_limits<double>::infinity();
  for (int s = 0; s < ns; ++s) {
    const Eigen::Vector3d d = data_.surface_position.row(s).transpose() - point;
    const double d2 = d.squaredNorm();
    if (d2 < nearest) {
      nearest = d2;
      r->contact_node = s;
    }
    const double rho = std::sqrt(d2 + l2);
    const Eigen::Vector3d e = d / rho;
    const double monomial[kDirectionMonomials] = {1.0,        e[0],        e[1],        e[2],        e[0] * e[0],
                                                  e[0] * e[1], e[0] * e[2], e[1] * e[1], e[1] * e[2], e[2] * e[2]};
    double s_power = 1.0;
    for (int m = 0; m < dent_order_; ++m) {
      s_power *= contact_length_ / rho;
      for (int i = 0; i < 3; ++i) {
        const double* coefficient = dent_storage + (i * dent_order_ + m) * kDirectionMonomials;
        double v = 0.0;
        for (int k = 0; k < kDirectionMonomials; ++k) v += coefficient[k] * monomial[k];
        u[3 * s + i] += s_power * v;
      }
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
