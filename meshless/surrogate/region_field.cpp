#include "meshless/surrogate/region_field.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <tuple>

namespace meshless {
namespace {

constexpr int kMaxFieldOrder = 8;        // lambda' (SurrogateFitOptions::IsValid)
constexpr int kMaxPositionMonomials = 6;  // position_order <= 2
constexpr int kMaxContactTerms = 60;      // 10 per contact order, c <= 6

SpatialBasis basis_of(const InducedFieldFit& f, const SurfaceFrame& frame) {
  return SpatialBasis(f.tangential_order, f.normal_order, f.contact_order, frame.contact_length / frame.length);
}

}  // namespace

int position_monomials(int order) {
  if (order < 0 || order > 2) throw std::invalid_argument("position_monomials: the order must be 0, 1 or 2");
  return (order + 1) * (order + 2) / 2;
}

void position_basis(const RegionField& field, const Eigen::Vector3d& point, double* out) {
  const Eigen::Vector3d local = field.frame.local(point) * (field.frame.length / field.radius);
  const double t1 = local.x(), t2 = local.y();
  const double all[kMaxPositionMonomials] = {1.0, t1, t2, t1 * t1, t1 * t2, t2 * t2};
  for (int q = 0; q < position_monomials(field.position_order); ++q) out[q] = all[q];
}

std::array<RegionAxisField, 3> region_shape(const std::vector<ContactFit>& fits) {
  std::array<RegionAxisField, 3> shape;
  for (const ContactFit& c : fits)
    for (int j = 0; j < 3; ++j) {
      shape[j].field_order = std::max(shape[j].field_order, c.axis[j].field_order);
      for (int i = 0; i < 3; ++i) {
        InducedFieldFit& f = shape[j].field[i];
        const InducedFieldFit& g = c.axis[j].field[i];
        f.tangential_order = std::max(f.tangential_order, g.tangential_order);
        f.normal_order = std::max(f.normal_order, g.normal_order);
        f.contact_order = std::max(f.contact_order, g.contact_order);
      }
    }
  return shape;
}

RegionField fit_region_field(const SurfaceNodes& surface, const ContactRegion& region,
                             const std::vector<ContactTrainingData>& data, double max_force,
                             const std::array<RegionAxisField, 3>& shape, int position_order,
                             const SurrogateFitOptions& options) {
  const int nc = static_cast<int>(data.size()), ns = surface.size();
  const int nq = position_monomials(position_order);
  if (nc < nq)
    throw std::invalid_argument(fmt::format(
        "fit_region_field: {} trained contacts cannot determine a position polynomial of degree {} ({} terms)", nc,
        position_order, nq));
  if (!(max_force > 0.0)) throw std::invalid_argument("fit_region_field: max_force must be > 0");
  const std::vector<double>& levels = data.front().levels;
  const int nl = static_cast<int>(levels.size());
  for (const ContactTrainingData& d : data)
    for (int j = 0; j < 3; ++j) {
      if (d.levels != levels || static_cast<int>(d.displacement[j].size()) != nl)
        throw std::invalid_argument("fit_region_field: every contact needs the same levels on every axis");
      for (const core::PointMatrix& u : d.displacement[j])
        if (u.rows() != ns || !u.allFinite())
          throw std::invalid_argument("fit_region_field: a training field has the wrong size or a non-finite value");
    }

  RegionField out;
  out.radius = region.radius;
  out.position_order = position_order;
  double length = 0.0;
  for (int s = 0; s < ns; ++s) length = std::max(length, (surface.position.row(s).transpose() - region.centre).norm());
  out.frame = SurfaceFrame::at(region.centre, region.normal, length,
                               options.contact_length > 0.0 ? options.contact_length : length);

  // Where each contact is: its position monomials and its offset in the frame's coordinates.
  Eigen::MatrixX3d local(ns, 3);
  for (int s = 0; s < ns; ++s) local.row(s) = out.frame.local(surface.position.row(s).transpose()).transpose();
  std::vector<std::array<double, kMaxPositionMonomials>> t(nc);
  std::vector<Eigen::Vector3d> contact_local(nc);
  for (int c = 0; c < nc; ++c) {
    const Eigen::Vector3d p = surface.position.row(data[c].contact).transpose();
    position_basis(out, p, t[c].data());
    contact_local[c] = out.frame.local(p);
  }
  std::vector<double> s(nl);
  for (int l = 0; l < nl; ++l) s[l] = levels[l] / max_force;

  // The design of one set of orders (a, b, c): rows (contact, node), columns (basis term, position monomial).
  auto design = [&](const SpatialBasis& basis) {
    Eigen::MatrixXd a(static_cast<Eigen::Index>(nc) * ns, static_cast<Eigen::Index>(basis.size()) * nq);
    std::vector<double> psi(basis.size());
    for (int c = 0; c < nc; ++c)
      for (int n = 0; n < ns; ++n) {
        const Eigen::Vector3d x = local.row(n).transpose();
        basis.evaluate(x, x - contact_local[c], psi.data());
        for (int k = 0; k < basis.size(); ++k)
          for (int q = 0; q < nq; ++q) a(c * ns + n, k * nq + q) = psi[k] * t[c][q];
      }
    return a;
  };
  std::map<std::tuple<int, int, int>, std::pair<Eigen::MatrixXd, ScaledLeastSquares>> factorised;

  double squared_error = 0.0;
  for (int j = 0; j < 3; ++j) {
    RegionAxisField& axis = out.axis[j];
    axis.field_order = shape[j].field_order;
    if (axis.field_order < 1 || axis.field_order > kMaxFieldOrder)
      throw std::invalid_argument("fit_region_field: field order outside [1, 8]");
    double u_scale = 0.0;
    for (const ContactTrainingData& d : data)
      for (const core::PointMatrix& u : d.displacement[j]) u_scale = std::max(u_scale, u.cwiseAbs().maxCoeff());
    if (!(u_scale > 0.0)) u_scale = 1.0;
    // Stage 1 as in fit_contact(): every node's least-squares force polynomial, per contact.
    const Eigen::MatrixXd v = force_powers(s, axis.field_order);
    const ScaledLeastSquares vls(v, options.rank_threshold);
    const Eigen::MatrixXd sigma_powers = force_powers(levels, axis.field_order);  // sigma in N
    for (int i = 0; i < 3; ++i) {
      InducedFieldFit& field = axis.field[i];
      field.tangential_order = shape[j].field[i].tangential_order;
      field.normal_order = shape[j].field[i].normal_order;
      field.contact_order = shape[j].field[i].contact_order;
      Eigen::MatrixXd nodal(static_cast<Eigen::Index>(nc) * ns, axis.field_order);
      std::vector<Eigen::MatrixXd> target(nc);
      bool noise = true;
      for (int c = 0; c < nc; ++c) {
        target[c].resize(ns, nl);
        for (int l = 0; l < nl; ++l) target[c].col(l) = data[c].displacement[j][l].col(i) / u_scale;
        noise = noise && target[c].cwiseAbs().maxCoeff() <= options.noise_floor;
        nodal.middleRows(static_cast<Eigen::Index>(c) * ns, ns) = vls.solve(target[c].transpose()).transpose();
      }
      const SpatialBasis basis = basis_of(field, out.frame);
      const auto key = std::make_tuple(field.tangential_order, field.normal_order, field.contact_order);
      auto it = factorised.find(key);
      if (it == factorised.end()) {
        Eigen::MatrixXd a = design(basis);
        ScaledLeastSquares ls(a, options.rank_threshold);
        it = factorised.emplace(key, std::make_pair(std::move(a), std::move(ls))).first;
      }
      const Eigen::MatrixXd& a = it->second.first;
      field.coefficients = noise ? Eigen::MatrixXd::Zero(a.cols(), axis.field_order) : it->second.second.solve(nodal);
      for (int p = 0; p < axis.field_order; ++p) field.coefficients.col(p) *= u_scale / std::pow(max_force, p + 1);
      // Against the training data in SI.
      const Eigen::MatrixXd per_node = a * field.coefficients;  // (contact, node) by power
      for (int c = 0; c < nc; ++c)
        squared_error += (per_node.middleRows(static_cast<Eigen::Index>(c) * ns, ns) * sigma_powers.transpose() -
                          target[c] * u_scale)
                             .squaredNorm();
    }
  }
  out.training_rms = std::sqrt(squared_error / (3.0 * nc * ns * nl));
  return out;
}

RegionFieldEvaluator::RegionFieldEvaluator(RegionField field, const core::PointMatrix& surface_position)
    : field_(std::move(field)), position_(surface_position) {
  const int ns = static_cast<int>(position_.rows());
  const int nq = position_monomials(field_.position_order);
  for (const RegionAxisField& a : field_.axis) {
    if (a.field_order < 1 || a.field_order > kMaxFieldOrder)
      throw std::invalid_argument("RegionFieldEvaluator: field order outside [1, 8]");
    columns_ += a.field_order * nq;
    for (const InducedFieldFit& f : a.field) {
      contact_order_ = std::max(contact_order_, f.contact_order);
      if (basis_of(f, field_.frame).size() * nq != f.coefficients.rows() || f.coefficients.cols() != a.field_order)
        throw std::invalid_argument("RegionFieldEvaluator: coefficients do not match the orders");
    }
  }
  if (10 * contact_order_ > kMaxContactTerms) throw std::invalid_argument("RegionFieldEvaluator: contact order above 6");
  smooth_ = Eigen::MatrixXd::Zero(3 * ns, columns_);
  // Each component's contact terms: as many rows as its largest contact order over the axes has (10 per order),
  // zero where an axis has fewer.
  for (int i = 0; i < 3; ++i) {
    int order = 0;
    for (const RegionAxisField& a : field_.axis) order = std::max(order, a.field[i].contact_order);
    dent_[i] = Eigen::MatrixXd::Zero(10 * order, columns_);
  }
  int offset = 0;  // first column of the axis
  for (const RegionAxisField& a : field_.axis) {
    for (int i = 0; i < 3; ++i) {
      const InducedFieldFit& f = a.field[i];
      const SpatialBasis basis = basis_of(f, field_.frame);
      int polynomial_terms = 0;
      for (const BasisTerm& term : basis.terms()) polynomial_terms += term.m == 0;
      const int contact_terms = basis.size() - polynomial_terms;
      // The contact terms come after the polynomial ones, by m then degree (surrogate_basis.hpp).
      for (int term = 0; term < contact_terms; ++term)
        for (int p = 0; p < a.field_order; ++p)
          for (int q = 0; q < nq; ++q)
            dent_[i](term, offset + p * nq + q) = f.coefficients((polynomial_terms + term) * nq + q, p);
      std::vector<double> psi(basis.size());
      for (int s = 0; s < ns; ++s) {
        const Eigen::Vector3d x = field_.frame.local(position_.row(s).transpose());
        basis.evaluate(x, psi.data());  // the polynomial terms do not depend on the probe
        for (int k = 0; k < polynomial_terms; ++k)
          for (int p = 0; p < a.field_order; ++p)
            for (int q = 0; q < nq; ++q)
              smooth_(3 * s + i, offset + p * nq + q) += psi[k] * f.coefficients(k * nq + q, p);
      }
    }
    offset += a.field_order * nq;
  }
}

int RegionFieldEvaluator::force_columns() const {
  return field_.axis[0].field_order + field_.axis[1].field_order + field_.axis[2].field_order;
}

void RegionFieldEvaluator::evaluate(const Eigen::Vector3d& point, const Eigen::Vector3d& force, double* u) const {
  double powers[3 * kMaxFieldOrder];
  int n = 0;
  for (int j = 0; j < 3; ++j) {
    double power = 1.0;
    for (int p = 0; p < field_.axis[j].field_order; ++p) powers[n++] = power *= force[j];
  }
  evaluate_powers(point, powers, u);
}

Eigen::MatrixXd RegionFieldEvaluator::nodal_at(const Eigen::Vector3d& point) const {
  const int columns = force_columns();
  Eigen::MatrixXd out(3 * position_.rows(), columns);
  std::vector<double> unit(columns, 0.0);
  for (int k = 0; k < columns; ++k) {
    unit[k] = 1.0;
    evaluate_powers(point, unit.data(), out.col(k).data());
    unit[k] = 0.0;
  }
  return out;
}

void RegionFieldEvaluator::evaluate_powers(const Eigen::Vector3d& point, const double* powers, double* u) const {
  const int ns = static_cast<int>(position_.rows());
  const int nq = position_monomials(field_.position_order);
  double t[kMaxPositionMonomials];
  position_basis(field_, point, t);
  // The combined force and position monomials sigma_j^p T_q, in the column order of smooth_ and dent_.
  double v_storage[3 * kMaxFieldOrder * kMaxPositionMonomials];
  int n = 0, k = 0;
  for (int j = 0; j < 3; ++j)
    for (int p = 0; p < field_.axis[j].field_order; ++p, ++k)
      for (int q = 0; q < nq; ++q) v_storage[n++] = powers[k] * t[q];
  const Eigen::Map<const Eigen::VectorXd> v(v_storage, n);
  Eigen::Map<Eigen::VectorXd> out(u, 3 * ns);
  out.noalias() = smooth_ * v;
  if (contact_order_ == 0) return;

  // The contact terms at X - p: their coefficients for this force and position first, then per node.
  double d_storage[3][kMaxContactTerms];
  for (int i = 0; i < 3; ++i) Eigen::Map<Eigen::VectorXd>(d_storage[i], dent_[i].rows()).noalias() = dent_[i] * v;
  const SpatialBasis contact(0, 0, contact_order_, field_.frame.contact_length / field_.frame.length);
  const Eigen::Vector3d p = field_.frame.local(point);
  double psi[1 + kMaxContactTerms];
  for (int s = 0; s < ns; ++s) {
    const Eigen::Vector3d offset = field_.frame.local(position_.row(s).transpose()) - p;
    contact.evaluate(offset, psi);  // psi[0] is the constant; the contact terms follow in the fields' order
    for (int i = 0; i < 3; ++i) {
      double sum = 0.0;
      for (Eigen::Index term = 0; term < dent_[i].rows(); ++term) sum += d_storage[i][term] * psi[1 + term];
      u[3 * s + i] += sum;
    }
  }
}

}  // namespace meshless
