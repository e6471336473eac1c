#include "meshless/surrogate/surrogate_basis.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace meshless {
namespace {

constexpr int kMaxPower = 16;      // powers tabulated per coordinate
constexpr int kContactDegree = 2;  // degree of the direction monomials of the contact terms (Kelvin: e_i e_j)

}  // namespace

SurfaceFrame SurfaceFrame::at(const Eigen::Vector3d& origin, const Eigen::Vector3d& normal, double length,
                              double contact_length) {
  if (!(length > 0.0) || !(normal.norm() > 0.0) || !(contact_length > 0.0))
    throw std::invalid_argument("SurfaceFrame: expected a non-zero normal and positive lengths");
  SurfaceFrame f;
  f.origin = origin;
  f.normal = normal.normalized();
  Eigen::Index axis = 0;
  f.normal.cwiseAbs().minCoeff(&axis);
  const Eigen::Vector3d e = Eigen::Vector3d::Unit(axis);
  f.tangent1 = (e - e.dot(f.normal) * f.normal).normalized();
  f.tangent2 = f.normal.cross(f.tangent1);
  f.length = length;
  f.contact_length = contact_length;
  return f;
}

Eigen::Vector3d SurfaceFrame::local(const Eigen::Vector3d& x) const {
  const Eigen::Vector3d d = (x - origin) / length;
  return {d.dot(tangent1), d.dot(tangent2), d.dot(normal)};
}

SpatialBasis::SpatialBasis(int tangential_order, int normal_order, int contact_order, double contact_length)
    : a_(tangential_order), b_(normal_order), c_(contact_order), ell_(contact_length) {
  if (a_ < 0 || b_ < 0 || c_ < 0) throw std::invalid_argument("SpatialBasis: orders must be >= 0");
  if (std::max({a_, b_, c_}) >= kMaxPower) throw std::invalid_argument("SpatialBasis: orders must be < 16");
  if (c_ > 0 && !(ell_ > 0.0))
    throw std::invalid_argument("SpatialBasis: contact terms need a contact length > 0");
  for (int degree = 0; degree <= a_; ++degree)
    for (int q = 0; q <= degree; ++q)
      for (int r = 0; r <= b_; ++r) terms_.push_back({degree - q, q, r, 0});
  for (int m = 1; m <= c_; ++m)
    for (int degree = 0; degree <= kContactDegree; ++degree)
      for (int q = 0; q <= degree; ++q)
        for (int r = 0; r <= degree - q; ++r) terms_.push_back({degree - q - r, q, r, m});
}

void SpatialBasis::evaluate(const Eigen::Vector3d& local, const Eigen::Vector3d& contact_offset,
                            double* out) const {
  // Powers once per coordinate, then products: a few dozen multiplications per point.
  double pw[3][kMaxPower], ew[3][kContactDegree + 1], sw[kMaxPower];
  const double rho = std::sqrt(contact_offset.squaredNorm() + ell_ * ell_);
  for (int k = 0; k < 3; ++k) {
    pw[k][0] = ew[k][0] = 1.0;
    for (int n = 1; n < kMaxPower; ++n) pw[k][n] = pw[k][n - 1] * local[k];
    for (int n = 1; n <= kContactDegree; ++n)
      ew[k][n] = ew[k][n - 1] * (c_ > 0 ? contact_offset[k] / rho : 0.0);
  }
  sw[0] = 1.0;
  for (int n = 1; n <= c_; ++n) sw[n] = sw[n - 1] * ell_ / rho;
  for (int k = 0; k < size(); ++k) {
    const BasisTerm& t = terms_[k];
    out[k] = t.m == 0 ? pw[0][t.p] * pw[1][t.q] * pw[2][t.r] : sw[t.m] * ew[0][t.p] * ew[1][t.q] * ew[2][t.r];
  }
}

Eigen::MatrixXd SpatialBasis::evaluate(const Eigen::MatrixX3d& local) const {
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> m(local.rows(), size());
  for (Eigen::Index i = 0; i < local.rows(); ++i) evaluate(local.row(i).transpose(), m.row(i).data());
  return m;
}

std::vector<int> SpatialBasis::subset(int tangential_order, int normal_order, int contact_order) const {
  std::vector<int> columns;
  for (int k = 0; k < size(); ++k) {
    const BasisTerm& t = terms_[k];
    const bool keep = t.m == 0 ? t.p + t.q <= tangential_order && t.r <= normal_order : t.m <= contact_order;
    if (keep) columns.push_back(k);
  }
  return columns;
}

}  // namespace meshless
