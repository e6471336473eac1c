#include "meshless/lrpim/rpim_shape_functions.hpp"

#include <Eigen/LU>
#include <cmath>
#include <sstream>

#include "meshless/mls/node_search.hpp"

namespace meshless::lrpim {

namespace {
std::string singular_message(const Eigen::Vector3d& x, int n, double rcond) {
  std::ostringstream s;
  s << "RPIM moment matrix [R P; P^T 0] is singular at (" << 1e3 * x.x() << ", " << 1e3 * x.y() << ", "
    << 1e3 * x.z() << ") mm with " << n << " support nodes (rcond " << rcond
    << "): the nodes are (nearly) coplanar or too few for the linear basis, or the multiquadric is too flat. "
       "Raise RpimParameters::num_neighbours, lower alpha_c, or refine the cloud there.";
  return s.str();
}
}  // namespace

SingularRpimMatrix::SingularRpimMatrix(const Eigen::Vector3d& x, int num_nodes, double rcond)
    : std::runtime_error(singular_message(x, num_nodes, rcond)), point_(x), num_nodes_(num_nodes), rcond_(rcond) {}

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
  const int m = n + 4;
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(m, m);
  for (int i = 0; i < n; ++i) {
    for (int j = i; j < n; ++j) g(i, j) = g(j, i) = std::pow((y.col(i) - y.col(j)).squaredNorm() + c2, q);
    g(i, n) = g(n, i) = 1.0;
    for (int k = 0; k < 3; ++k) g(i, n + 1 + k) = g(n + 1 + k, i) = y(k, i);
  }
  const int cols = with_gradients ? 4 : 1;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(m, cols);
  for (int i = 0; i < n; ++i) {
    const double r2 = y.col(i).squaredNorm();
    rhs(i, 0) = std::pow(r2 + c2, q);
    if (with_gradients) {
      // d/dX of ((|X_i - X|/s)^2 + c2)^q = q (.)^(q-1) * 2 (X - X_i)/s^2 = -2 q (.)^(q-1) y_i / s
      const double f = -2.0 * q * std::pow(r2 + c2, q - 1.0) / s;
      for (int k = 0; k < 3; ++k) rhs(i, 1 + k) = f * y(k, i);
    }
  }
  rhs(n, 0) = 1.0;  // p(X) = [1, 0, 0, 0] in the basis centred at X
  if (with_gradients)
    for (int k = 0; k < 3; ++k) rhs(n + 1 + k, 1 + k) = 1.0 / s;
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
