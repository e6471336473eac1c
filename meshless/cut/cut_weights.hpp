#pragma once
// The weight modifier h_i(X) of a cut (paper §4, eqs. 29-32): MLS weights w_i(X) h_i(X) make the shape functions
// discontinuous across the incision. Two treatments:
//
//  * enrichment (the paper's proposed model, eqs. 29-32 in 3-D, docs/MESHLESS.md §5):
//        phi(X) = s(X) / d(X)                   eq. 31, with s and d from core::CutFrame (eq. 29 in 3-D)
//        Phi(X) = phi(X) * min(1, r(X) / l)     r = distance to the crack front, l = the front transition length
//        h_i(X) = (1 + sigma_i Phi(X)) / 2      eq. 32 for the node's side sigma_i = +-1
//    Behind the front phi = +-1 exactly, so a node contributes nothing (h_i = 0) to points on the other side farther
//    than l from the front. Around the front h_i varies continuously, and the factor min(1, r/l) closes the crack at
//    the front (the jump of h_i across the cut vanishes there; with l = 0 the paper's phi is used as it stands, and the
//    shape functions stay discontinuous at the front itself).
//  * visibility (the baseline meshless cutting model): h_i(X) = 0 when the segment X_i -> X crosses the cut, else 1.
//    No smooth front.
//
// Only nodes whose support meets the cut are modified (the paper: nodes nearer the cut than their rho_i); for all
// others h_i = 1.
//
// Rules for the degenerate cases (never 0/0, never a non-finite gradient):
//  * a node on the cut (|s| <= core::RuledSurface::kOnCutTolerance) belongs to the s > 0 side;
//  * a point on the cut takes the side it is given (the `side` argument: +1 or -1, e.g. the lip a boundary point
//    lies on), or the s > 0 side when it is given 0;
//  * a point on the front (d = 0 outside the slab behind it) has phi = 0 and a zero gradient.
//
// Lifetime: copies the cut; references `nodes` and `radii`, which must outlive it. Thread safety: const calls are
// safe from several threads (the per-point frame is cached per thread).
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/ruled_surface.hpp"
#include "core/tet_mesh.hpp"

namespace meshless {

enum class CutTreatment {
  enrichment,  ///< eqs. 29-32 with a continuous front (the paper's proposed model)
  visibility,  ///< line of sight, h in {0, 1} (the baseline)
};

/// "enrichment" / "visibility" (the case's /meshless/enrichment) to the treatment. Throws std::invalid_argument.
CutTreatment cut_treatment_from_name(const std::string& name);
const char* to_string(CutTreatment treatment);

class CutWeights {
 public:
  /// @param cut the incision [m];  @param nodes #nodes by 3 [m];  @param radii #nodes support radii rho_i [m]
  /// @param front_transition l [m], >= 0 (enrichment only; 0 = the paper's phi without a transition)
  CutWeights(core::RuledSurface cut, const core::PointMatrix& nodes, const Eigen::VectorXd& radii,
             CutTreatment treatment, double front_transition);

  /// h_i(X) in [0, 1], and dh_i/dX [1/m] into *grad when not null. `side` resolves points on the cut (see above).
  /// Matches meshless::WeightModifier.
  double operator()(int node, const Eigen::Vector3d& x, int side, Eigen::Vector3d* grad) const;

  /// The enrichment function Phi(X) in [-1, 1] (for the side-independent part of h) and its gradient.
  double enrichment_function(const Eigen::Vector3d& x, int side, Eigen::Vector3d* grad) const;

  bool modifies(int node) const { return modified_[node] != 0; }  ///< its support meets the cut
  int node_side(int node) const { return node_side_[node]; }     ///< sigma_i, +1 or -1
  int num_modified() const;
  const core::RuledSurface& cut() const { return cut_; }
  CutTreatment treatment() const { return treatment_; }
  double front_transition() const { return front_transition_; }

 private:
  core::RuledSurface cut_;
  const core::PointMatrix* nodes_;
  CutTreatment treatment_;
  double front_transition_;
  std::vector<std::int8_t> node_side_;
  std::vector<char> modified_;
  std::uint64_t id_;  // keys the per-thread frame cache
};

}  // namespace meshless
