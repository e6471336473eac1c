#include "meshless/lrpim/rpim_shape_functions.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <cmath>
#include <sstream>

#include "meshless/mls/node_search.hpp"

namespace meshless::lrpim {

namespace {
std::string singular_message(const Eigen::Vector3d& x, int n, double rcond, double spread) {
  std::ostringstream s;
  s << "RPIM moment matrix [R P; P^T 0] is singular at (" << 1e3 * x.x() << ", " << 1e3 * x.y() << ", "
    << 1e3 * x.z() << ") mm with " << n << " support nodes (";
  if (std::isnan(rcond))
    s << "the nodes' smallest coordinate variance is " << spread << " d_c^2, below RpimParameters::min_spread";
  else
    s << "rcond " << rcond;
  s << "): the nodes are (nearly) coplanar or too few for the linear basis, or the multiquadric is too flat. "
       "Raise RpimParameters::num_neighbours, lower alpha_c, or refine the cloud there.";
  return s.str();
}
}  // namespace

SingularRpimMatrix::SingularRpimMatrix(const Eigen::Vector3d& x, int num_nodes, double rcond, double spread)
    : std::runtime_error(singular_message(x, num_nodes, rcond, spread)),
      point_(x),
      num_nodes_(num_nodes),
      rcond_(rcond),
      spread_(spread) {}

RpimShapeFunctions::RpimShapeFunctions(const core::PointMatrix& nodes, const NodeSearch& search, double spacing,
                                       RpimParameters parameters)
    : nodes_(&nodes), search_(&search), spacing_(spacing), parameters_(parameters) {
  if (!(spacing > 0.0) || !std::isfinite(spacing))
    throw std::invalid_argument("RpimShapeFunctions: the nodal spacing d_c must be a positive length in metres");
  if (parameters.num_neighbours < 4)
    throw std::invalid_argument("RpimShapeFunctions: num_neighbours must be >= 4 (the linear basis has 4 terms)");
  if (!(parameters.q > 0.0) || !(parameters.alpha_c > 0.0))
    throw std::invalid_argument("RpimShapeFunctions: the multiquadric needs q > 0 and alpha_c > 0");
}

RpimEvaluation RpimShapeFunctions::evaluate(const Eigen::Vector3d& x, bool with_gradients) const {
  RpimEvaluation e;
  evaluate(x, with_gradients, &e);
  return e;
}

void RpimShapeFunctions::evaluate(const Eigen::Vector3d& x, bool with_gradients, RpimEvaluation* out) const {
  if (!x.allFinite()) throw std::invalid_argument("RpimShapeFunctions::evaluate: non-finite point");
  out->nodes = search_->nearest(x, parameters_.num_neighbours);
  const int n = static_cast<int>(out->nodes.size());
  double s = spacing_;
  if (node_spacing_ && !node_spacing_->empty()) {
    s = 0.0;
    for (int i : out->nodes) s += (*node_spacing_)[i];
    s /= static_cast<double>(n);
  }
  const double c2 = parameters_.alpha_c * parameters_.alpha_c, q = parameters_.q;
  // Node coordinates relative to X in units of d_c.
  Eigen::Matrix3Xd y(3, n);
  for (int i = 0; i < n; ++i) y.col(i) = (nodes_->row(out->nodes[i]).transpose() - x) / s;
  // The rank test of P (RpimParameters::min_spread): the smallest eigenvalue of the nodes' covariance.
  {
    const Eigen::Vector3d mean = y.rowwise().mean();
    const Eigen::Matrix3d covariance = (y.colwise() - mean) * (y.colwise() - mean).transpose() / n;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
    eigen.computeDirect(covariance, Eigen::EigenvaluesOnly);
    out->spread = eigen.eigenvalues()[0];
    if (!(out->spread >= parameters_.min_spread)) throw SingularRpimMatrix(x, n, std::nan(""), out->spread);
  }
  // The multiquadric's n(n+1)/2 node-pair terms and its n terms at X, one power each: the gradient's (.)^(q-1)
  // below is (.)^q / (.), not a second power (the powers were a quarter of the LRPIM's set-up).
  const int pairs = n * (n + 1) / 2;
  Eigen::ArrayXd base(pairs + n);
  for (int i = 0, k = 0; i < n; ++i)
    for (int j = i; j < n; ++j, ++k) base[k] = (y.col(i) - y.col(j)).squaredNorm() + c2;
  for (int i = 0; i < n; ++i) base[pairs + i] = y.col(i).squaredNorm() + c2;
  const Eigen::ArrayXd power = base.pow(q);
  const int m = n + 4;
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(m, m);
  for (int i = 0, k = 0; i < n; ++i) {
    for (int j = i; j < n; ++j, ++k) g(i, j) = g(j, i) = power[k];
    g(i, n) = g(n, i) = 1.0;
    for (int c = 0; c < 3; ++c) g(i, n + 1 + c) = g(n + 1 + c, i) = y(c, i);
  }
  const int cols = with_gradients ? 4 : 1;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(m, cols);
  for (int i = 0; i < n; ++i) {
    rhs(i, 0) = power[pairs + i];
    if (with_gradients) {
      // d/dX of ((|X_i - X|/s)^2 + c2)^q = q (.)^(q-1) * 2 (X - X_i)/s^2 = -2 q (.)^(q-1) y_i / s
      const double f = -2.0 * q * (power[pairs + i] / base[pairs + i]) / s;
      for (int c = 0; c < 3; ++c) rhs(i, 1 + c) = f * y(c, i);
    }
  }
  rhs(n, 0) = 1.0;  // p(X) = [1, 0, 0, 0] in the basis centred at X
  if (with_gradients)
    for (int c = 0; c < 3; ++c) rhs(n + 1 + c, 1 + c) = 1.0 / s;
  // G is symmetric indefinite (saddle point): partial-pivoting LU.
  const Eigen::PartialPivLU<Eigen::MatrixXd> lu(g);
  const double rcond = lu.rcond();
  out->rcond = rcond;
  if (!(rcond >= parameters_.min_rcond)) throw SingularRpimMatrix(x, n, rcond);
  const Eigen::MatrixXd sol = lu.solve(rhs);
  if (!sol.allFinite()) throw SingularRpimMatrix(x, n, rcond);
  out->phi = sol.col(0).head(n);
  if (with_gradients)
    out->dphi = sol.block(0, 1, n, 3).transpose();
  else
    out->dphi.resize(3, 0);
}

}  // namespace meshless::lrpim
