#include "meshless/mls/mls_shape_functions.hpp"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "meshless/mls/cubic_spline_weight.hpp"
#include "meshless/mls/node_search.hpp"
#include "meshless/mls/support_radii.hpp"

namespace meshless {

namespace {

std::string singular_message(const Eigen::Vector3d& x, int num_covering, int num_weighted, double rcond) {
  std::string msg = fmt::format(
      "MLS moment matrix A(X) is singular at X = ({:.6g}, {:.6g}, {:.6g}) mm: {} covering neighbour(s)",
      1e3 * x.x(), 1e3 * x.y(), 1e3 * x.z(), num_covering);
  if (num_weighted != num_covering) msg += fmt::format(", {} with non-zero weight", num_weighted);
  msg += fmt::format(" (the linear basis needs >= 4 non-coplanar ones), rcond = {:.3g}", rcond);
  return msg;
}

/// A node with a non-zero weight at the evaluation point.
struct WeightedNode {
  int node;
  double w;            // w_i(X), modifier included
  Eigen::Vector3d dw;  // d w_i / d X [1/m], modifier included (zero without gradients)
};

}  // namespace

SingularMomentMatrix::SingularMomentMatrix(const Eigen::Vector3d& x, int num_covering, int num_weighted,
                                           double rcond)
    : std::runtime_error(singular_message(x, num_covering, num_weighted, rcond)),
      point_(x),
      num_covering_(num_covering),
      num_weighted_(num_weighted),
      rcond_(rcond) {}

MlsShapeFunctions::MlsShapeFunctions(const core::PointMatrix& nodes, const SupportRadii& radii,
                                     const NodeSearch& search, MlsOptions options)
    : nodes_(&nodes), radii_(&radii), search_(&search), options_(options) {
  if (radii.size() != nodes.rows() || search.num_nodes() != nodes.rows())
    throw std::invalid_argument(
        fmt::format("MlsShapeFunctions: {} nodes but {} radii and a search over {} nodes", nodes.rows(),
                    radii.size(), search.num_nodes()));
  if (&search.nodes() != &nodes)
    throw std::invalid_argument("MlsShapeFunctions: the search was built on a different node matrix");
}

MlsEvaluation MlsShapeFunctions::evaluate(const Eigen::Vector3d& x, bool with_gradients, int side) const {
  MlsEvaluation out;
  evaluate(x, with_gradients, &out, side);
  return out;
}

void MlsShapeFunctions::evaluate(const Eigen::Vector3d& x, bool with_gradients, MlsEvaluation* out, int side) const {
  if (!x.allFinite())
    throw std::invalid_argument(
        fmt::format("MlsShapeFunctions::evaluate: non-finite point ({}, {}, {})", x.x(), x.y(), x.z()));

  // Per-thread scratch: evaluation runs once per quadrature point, so avoid allocating on every call.
  thread_local std::vector<NodeHit> hits;
  thread_local std::vector<WeightedNode> weighted;
  search_->covering(x, radii_->radii(), radii_->max_radius(), &hits);
  weighted.clear();

  const core::PointMatrix& nodes = *nodes_;
  const Eigen::VectorXd& rho = radii_->radii();
  int num_covering = 0;
  for (const NodeHit& hit : hits) {
    const double rho_i = rho[hit.node];  // hit.distance_sq < rho_i^2 (NodeSearch::covering)
    ++num_covering;
    const double r = std::sqrt(hit.distance_sq);
    const WeightAndSlope ws = cubic_spline_weight_with_slope(r / rho_i);  // eq. 8, s_i = |X - X_i| / rho_i
    WeightedNode wn{hit.node, ws.w, Eigen::Vector3d::Zero()};
    if (with_gradients && r > 0.0) {
      // d s_i / d X = (X - X_i) / (r rho_i); at r = 0 the slope dw/ds(0) = 0 so the gradient is 0.
      wn.dw = (ws.dw_ds / (r * rho_i)) * (x - nodes.row(hit.node).transpose());
    }
    if (modifier_) {
      Eigen::Vector3d grad_h = Eigen::Vector3d::Zero();
      const double h = modifier_(hit.node, x, side, with_gradients ? &grad_h : nullptr);
      if (!(h >= 0.0 && h <= 1.0) || !grad_h.allFinite())
        throw std::domain_error(fmt::format(
            "MlsShapeFunctions: weight modifier returned h = {} for node {} at ({:.6g}, {:.6g}, {:.6g}) mm; "
            "it must lie in [0, 1] with a finite gradient",
            h, hit.node, 1e3 * x.x(), 1e3 * x.y(), 1e3 * x.z()));
      if (with_gradients) wn.dw = h * wn.dw + wn.w * grad_h;  // product rule on h_i(X) w_i(X)
      wn.w *= h;
    }
    // s_i < 1 gives w_i > 0, so only the modifier (or underflow right at the sphere's edge) zeroes a weight.
    if (wn.w == 0.0 && (!with_gradients || wn.dw.isZero(0.0))) continue;
    weighted.push_back(wn);
  }
  const int n = static_cast<int>(weighted.size());
  if (n < 4) throw SingularMomentMatrix(x, num_covering, n, 0.0);
  // Ascending node ids: deterministic output independent of the KD-tree's traversal order.
  std::sort(weighted.begin(), weighted.end(),
            [](const WeightedNode& a, const WeightedNode& b) { return a.node < b.node; });

  // Shifted, scaled basis p(Y) = [1, (Y - X)/h]; so p(X) = e_0 and p_,k(X) = e_{k+1} / h.
  double h = 0.0;
  for (const WeightedNode& wn : weighted) h = std::max(h, rho[wn.node]);
  const double inv_h = 1.0 / h;
  thread_local Eigen::Matrix<double, 4, Eigen::Dynamic> p;  // 4 by n, p(X_i) in the scaled basis
  p.resize(4, n);
  Eigen::Matrix4d a = Eigen::Matrix4d::Zero();
  for (int j = 0; j < n; ++j) {
    const WeightedNode& wn = weighted[j];
    p(0, j) = 1.0;
    p.block<3, 1>(1, j) = (nodes.row(wn.node).transpose() - x) * inv_h;
    a.noalias() += wn.w * p.col(j) * p.col(j).transpose();  // eq. 3
  }

  const Eigen::LLT<Eigen::Matrix4d> llt(a);
  const double rcond = llt.info() == Eigen::Success ? llt.rcond() : 0.0;
  if (!(rcond >= options_.min_rcond)) throw SingularMomentMatrix(x, num_covering, n, rcond);

  // gamma = A^-1 p(X). One step of iterative refinement (a 4x4 product and solve) keeps sum_i Phi_i = 1 to
  // round-off even when A is near the rcond threshold; on healthy clouds it changes nothing measurable.
  const Eigen::Vector4d e0 = Eigen::Vector4d::UnitX();
  Eigen::Vector4d gamma = llt.solve(e0);
  gamma += llt.solve(e0 - a * gamma);

  out->rcond = rcond;
  out->nodes.resize(n);
  out->phi.resize(n);
  for (int j = 0; j < n; ++j) {
    out->nodes[j] = weighted[j].node;
    out->phi[j] = weighted[j].w * gamma.dot(p.col(j));  // eq. 6
  }
  if (!with_gradients) {
    out->dphi.resize(3, 0);
  } else {
    // A_,k = sum_i w_i,k p_i p_i^T; gamma_,k = A^-1 (p_,k - A_,k gamma).
    Eigen::Matrix<double, 4, 3> rhs = Eigen::Matrix<double, 4, 3>::Zero();
    rhs.bottomRows<3>().diagonal().setConstant(inv_h);
    for (int j = 0; j < n; ++j) {
      const double pg = p.col(j).dot(gamma);
      rhs.noalias() -= p.col(j) * (pg * weighted[j].dw.transpose());  // A_,k gamma, all three k at once
    }
    Eigen::Matrix<double, 4, 3> dgamma = llt.solve(rhs);
    out->dphi.resize(3, n);
    for (int j = 0; j < n; ++j) {
      const double pg = p.col(j).dot(gamma);
      out->dphi.col(j) = weighted[j].w * (dgamma.transpose() * p.col(j)) + pg * weighted[j].dw;
    }
  }
  if (!out->phi.allFinite() || !out->dphi.allFinite()) throw SingularMomentMatrix(x, num_covering, n, rcond);
}

}  // namespace meshless
