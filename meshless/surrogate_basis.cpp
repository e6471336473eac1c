#include "meshless/surrogate_basis.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace meshless {

SurfaceFrame SurfaceFrame::at(const Eigen::Vector3d& origin, const Eigen::Vector3d& normal, double length) {
  if (!(length > 0.0) || !(normal.norm() > 0.0))
    throw std::invalid_argument("SurfaceFrame: expected a non-zero normal and a positive length");
  SurfaceFrame f;
  f.origin = origin;
  f.normal = normal.normalized();
  Eigen::Index axis = 0;
  f.normal.cwiseAbs().minCoeff(&axis);
  const Eigen::Vector3d e = Eigen::Vector3d::Unit(axis);
  f.tangent1 = (e - e.dot(f.normal) * f.normal).normalized();
  f.tangent2 = f.normal.cross(f.tangent1);
  f.length = length;
  return f;
}

Eigen::Vector3d SurfaceFrame::local(const Eigen::Vector3d& x) const {
  const Eigen::Vector3d d = (x - origin) / length;
  return {d.dot(tangent1), d.dot(tangent2), d.dot(normal)};
}

SpatialBasis::SpatialBasis(int tangential_order, int normal_order) : a_(tangential_order), b_(normal_order) {
  if (a_ < 0 || b_ < 0) throw std::invalid_argument("SpatialBasis: orders must be >= 0");
  for (int degree = 0; degree <= a_; ++degree)
    for (int q = 0; q <= degree; ++q)
      for (int r = 0; r <= b_; ++r) exponents_.push_back({degree - q, q, r});
}

void SpatialBasis::evaluate(const Eigen::Vector3d& local, double* out) const {
  // Powers once per coordinate, then products: a few dozen multiplications per point.
  const int n = std::max(a_, b_) + 1;
  double pw[3][16];
  if (n > 16) throw std::invalid_argument("SpatialBasis: orders above 15 are not supported");
  for (int c = 0; c < 3; ++c) {
    pw[c][0] = 1.0;
    for (int k = 1; k < n; ++k) pw[c][k] = pw[c][k - 1] * local[c];
  }
  for (int k = 0; k < size(); ++k) {
    const std::array<int, 3>& e = exponents_[k];
    out[k] = pw[0][e[0]] * pw[1][e[1]] * pw[2][e[2]];
  }
}

Eigen::MatrixXd SpatialBasis::evaluate(const Eigen::MatrixX3d& local) const {
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> m(local.rows(), size());
  for (Eigen::Index i = 0; i < local.rows(); ++i) evaluate(local.row(i).transpose(), m.row(i).data());
  return m;
}

std::vector<int> SpatialBasis::subset(int tangential_order, int normal_order) const {
  std::vector<int> columns;
  for (int k = 0; k < size(); ++k) {
    const std::array<int, 3>& e = exponents_[k];
    if (e[0] + e[1] <= tangential_order && e[2] <= normal_order) columns.push_back(k);
  }
  return columns;
}

}  // namespace meshless
