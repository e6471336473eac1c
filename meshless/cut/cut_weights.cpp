#include "meshless/cut/cut_weights.hpp"

#include <fmt/format.h>

#include <atomic>
#include <cmath>
#include <stdexcept>

namespace meshless {
namespace {

std::atomic<std::uint64_t> next_id{1};

/// Phi and its gradient at the last point evaluated on this thread: the modifier is called once per covering node
/// for the same point, so the frame is computed once per point.
struct FrameCache {
  std::uint64_t owner = 0;
  Eigen::Vector3d x = Eigen::Vector3d::Constant(NAN);
  int side = 0;
  double phi = 0.0;
  Eigen::Vector3d grad = Eigen::Vector3d::Zero();
};

}  // namespace

CutTreatment cut_treatment_from_name(const std::string& name) {
  if (name == "enrichment") return CutTreatment::enrichment;
  if (name == "visibility") return CutTreatment::visibility;
  throw std::invalid_argument(fmt::format("unknown cut treatment \"{}\" (expected enrichment or visibility)", name));
}

const char* to_string(CutTreatment treatment) {
  return treatment == CutTreatment::enrichment ? "enrichment" : "visibility";
}

CutWeights::CutWeights(core::RuledSurface cut, const core::PointMatrix& nodes, const Eigen::VectorXd& radii,
                       CutTreatment treatment, double front_transition)
    : cut_(std::move(cut)), nodes_(&nodes), treatment_(treatment), front_transition_(front_transition), id_(next_id++) {
  if (!(front_transition >= 0.0) || !std::isfinite(front_transition))
    throw std::invalid_argument("CutWeights: the front transition length must be finite and >= 0");
  if (radii.size() != nodes.rows())
    throw std::invalid_argument("CutWeights: one support radius per node is needed");
  const Eigen::Index n = nodes.rows();
  node_side_.resize(n);
  modified_.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const core::CutFrame f = cut_.frame(nodes.row(i).transpose());
    node_side_[i] = f.s >= -core::RuledSurface::kOnCutTolerance ? 1 : -1;  // a node on the cut: the s > 0 side
    modified_[i] = f.distance < radii[i];  // paper §4: only nodes whose support meets the cut
  }
}

int CutWeights::num_modified() const {
  int count = 0;
  for (char m : modified_) count += m;
  return count;
}

double CutWeights::enrichment_function(const Eigen::Vector3d& x, int side, Eigen::Vector3d* grad) const {
  thread_local FrameCache cache;
  if (cache.owner == id_ && cache.side == side && cache.x == x) {
    if (grad) *grad = cache.grad;
    return cache.phi;
  }
  const core::CutFrame f = cut_.frame(x);
  double phi = 0.0;
  Eigen::Vector3d grad_phi = Eigen::Vector3d::Zero();
  if (f.behind_front) {
    // eq. 31 behind the front: d = |s|, so phi = sign(s) exactly (zero gradient); on the cut, the side given.
    const bool on_cut = std::abs(f.s) <= core::RuledSurface::kOnCutTolerance;
    phi = on_cut ? (side < 0 ? -1.0 : 1.0) : (f.s > 0.0 ? 1.0 : -1.0);
  } else if (f.distance > 0.0) {
    // eq. 31 past the front: phi = s / d, grad phi = (grad s d - s grad d) / d^2.
    phi = f.s / f.distance;
    grad_phi = (f.grad_s * f.distance - f.s * f.grad_distance) / (f.distance * f.distance);
  }  // else: on the front itself, phi = 0 with a zero gradient (the defined rule)
  if (front_transition_ > 0.0) {
    Eigen::Vector3d grad_r;
    const double r = cut_.front_distance(x, &grad_r);
    if (r < front_transition_) {
      // Phi = phi r / l near the front: continuous there, and the factor r/l bounds r * grad phi (|grad phi| ~ 1/d
      // with d = r past the front), so the gradient stays finite.
      grad_phi = grad_phi * (r / front_transition_) + phi * grad_r / front_transition_;
      phi *= r / front_transition_;
    }
  }
  cache = {id_, x, side, phi, grad_phi};
  if (grad) *grad = grad_phi;
  return phi;
}

double CutWeights::operator()(int node, const Eigen::Vector3d& x, int side, Eigen::Vector3d* grad) const {
  if (grad) grad->setZero();
  if (!modified_[node]) return 1.0;
  const Eigen::Vector3d xi = nodes_->row(node).transpose();
  if (treatment_ == CutTreatment::visibility) {
    // A point on the cut is moved a nanometre off it, to the side it is given, so the line of sight is decided for
    // that lip (the weight is 0 or 1, the shift changes nothing else).
    Eigen::Vector3d target = x;
    if (side != 0) {
      const core::CutFrame f = cut_.frame(x);
      if (std::abs(f.s) <= core::RuledSurface::kOnCutTolerance) target += 1e-9 * side * f.grad_s;
    }
    return cut_.segment_crosses(xi, target) ? 0.0 : 1.0;
  }
  Eigen::Vector3d grad_phi;
  const double phi = enrichment_function(x, side, grad ? &grad_phi : nullptr);
  const double sigma = node_side_[node];
  if (grad) *grad = 0.5 * sigma * grad_phi;
  // eq. 32 with the node's side; clamp the round-off of 1 -+ phi at phi = -+1.
  return std::clamp(0.5 * (1.0 + sigma * phi), 0.0, 1.0);
}

}  // namespace meshless
