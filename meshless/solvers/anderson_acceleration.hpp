#pragma once
// Anderson acceleration of a fixed-point iteration u <- u + f(u) (Walker & Ni 2011, "Anderson acceleration for
// fixed-point iterations", SIAM J. Numer. Anal. 49(4), the "type II" form of their Algorithm AA).
//
// Why the EFG needs it: Newton on kept factors (EfgOptions::refactor_contraction) is the fixed-point iteration
// f(u) = -K0^-1 R(u) with K0 an earlier tangent. It converges linearly, by the ratio of how far the current
// tangent has moved from K0: on lung_small (k = 1) about 0.2 per iteration, 6 to 11 iterations a step. Each
// iteration costs a residual assembly and a back-substitution. Anderson mixes the last `depth` updates so that
// the combination cancels the slow directions, a secant (multisecant Broyden) correction of K0 built from
// vectors the iteration computes anyway: no extra assembly and no extra solve.
//
// Not thread-safe; one instance per Newton iteration sequence. Units are those of u (metres for the EFG's
// nodal parameters); the least-squares problem is scale-invariant.
#include <Eigen/Dense>

#include <deque>

namespace meshless {

class AndersonAcceleration {
 public:
  /// depth: how many earlier iterate differences the mix uses (m of Walker & Ni); 0 turns the mixing off, and
  /// next_update() then returns f unchanged.
  explicit AndersonAcceleration(int depth);

  /// Forget the history: the map changed (new factors, a restored state).
  void reset();
  /// Start a new sequence of iterates (the next time step on the same factors) but keep the stored differences.
  /// A pair (dU, dF) from two iterates of one step is a secant of the tangent, -K0^-1 dR = -K0^-1 K dU, which does
  /// not depend on the step's load or history: it stays a good guide while the tangent moves slowly. No difference
  /// is ever taken across the two sequences.
  void start_sequence();

  /// The update to add to u, given the iterate u and its plain fixed-point update f = f(u):
  /// f - (dU + dF) gamma, where gamma minimises ||f - dF gamma|| over the stored differences
  /// dU = [u_k - u_{k-1}, ...] and dF = [f_k - f_{k-1}, ...]. Returns f itself on the first call after reset().
  /// A column that is linearly dependent on the others is dropped (the least-squares solve is rank-revealing).
  Eigen::VectorXd next_update(const Eigen::VectorXd& u, const Eigen::VectorXd& f);

  int depth() const { return depth_; }
  /// Differences held now (<= depth).
  int history() const { return static_cast<int>(du_.size()); }

 private:
  int depth_;
  Eigen::VectorXd last_u_, last_f_;
  std::deque<Eigen::VectorXd> du_, df_;  // newest at the back
};

}  // namespace meshless
