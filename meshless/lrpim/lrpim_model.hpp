#pragma once
// The LRPIM model (Liu & Gu 2001; for soft tissue, Zhou et al., the paper's ref. [32]): RPIM trial functions
// (meshless/lrpim/rpim_shape_functions.hpp) in the local Petrov-Galerkin weak form of Atluri's MLPG, one
// local sub-domain per node with the cubic spline as the test function, the Kelvin law of core/kelvin_law.hpp
// with one internal state per quadrature point, and Newton on the consistent tangent per time step.
// docs/LRPIM.md.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "core/kelvin_law.hpp"
#include "meshless/lrpim/lrpim_problem.hpp"
#include "meshless/mls/node_search.hpp"

namespace meshless::lrpim {

/// One quadrature point of a node's local weak form, with the trial functions tabulated there (the cloud does
/// not move: small strain, so they are computed once).
struct LocalIntegrationPoint {
  int test_node = -1;        ///< the node whose equations this point contributes to
  double weight = 0.0;       ///< [m^3] volume, [m^2] boundary
  double v = 0.0;            ///< test function value
  Eigen::Vector3d dv;        ///< grad v [1/m] (volume points)
  Eigen::Vector3d normal;    ///< outward unit normal (reaction points on displacement faces); zero for volume
  Eigen::Vector3d x;         ///< [m]
  double stiffness = 0.0;    ///< k_s(x) [Pa/m] (elastic-support points)
  std::vector<int> support;  ///< #n trial nodes
  Eigen::VectorXd phi;       ///< #n (elastic-support points; empty otherwise)
  Eigen::Matrix<double, 3, Eigen::Dynamic> dphi;  ///< 3 by #n [1/m] (volume and reaction points)
};

using LrpimMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;

/// The body's global balance at the current state: the net force [N] and moment about the origin [N m] of the
/// applied traction and of the elastic support's reaction, each integrated over the whole surface (a degree-2
/// rule per triangle, independent of the test functions), beside the same sums as the local equations weight
/// them (sum over all test nodes of the boundary terms, each point's v_i). A Galerkin method whose test
/// functions sum to 1 balances exactly (the internal forces cancel); MLPG's local equations need not:
/// docs/LRPIM.md §5.
struct LrpimGlobalBalance {
  Eigen::Vector3d applied_force = Eigen::Vector3d::Zero(), applied_moment = Eigen::Vector3d::Zero();
  Eigen::Vector3d support_force = Eigen::Vector3d::Zero(), support_moment = Eigen::Vector3d::Zero();
  /// sum_i int v_i s t-bar dA and sum_i int v_i (-k_s u) dA over the local boundaries
  Eigen::Vector3d test_weighted_applied = Eigen::Vector3d::Zero(),
                  test_weighted_support = Eigen::Vector3d::Zero();
};

/// The fictitious body force b(X) = lambda_F + lambda_M x (X - X_c) / L of LrpimProblem::balance_rigid_modes, as
/// the local equations weight it (sum over the test nodes of int v_i b dV): what the local equations' quadrature
/// left out of the body's balance.
struct LrpimBalanceCorrection {
  bool active = false;  ///< the six balance equations were imposed
  Eigen::Vector3d net_force = Eigen::Vector3d::Zero();   ///< [N]
  Eigen::Vector3d net_moment = Eigen::Vector3d::Zero();  ///< [N m] about the origin
};

/// Per step: what Newton did.
struct LrpimStepRecord {
  double time = 0.0;  ///< [s]
  int newton_iterations = 0;
  double residual = 0.0;          ///< final ||R|| / reference
  std::vector<double> residuals;  ///< ||R|| / reference at every iteration (the first before any solve)
  int factorisations = 0;  ///< tangents factorised in this step (preconditioner set-ups with petsc_krylov)
  int rejected_mixes = 0;  ///< Anderson-mixed updates that raised ||R|| and were replaced by the plain update
  double wall_seconds = 0.0, assembly_seconds = 0.0, solve_seconds = 0.0;  ///< this step's
};

/// The load of an LrpimProblem alone (its traction, ramp and step times): what LrpimModel::restart replaces.
struct LrpimLoad {
  std::function<Eigen::Vector3d(const Eigen::Vector3d&)> traction;  ///< [Pa] at full load (LrpimProblem::traction)
  std::function<double(double)> load_scale;                         ///< LrpimProblem::load_scale
  std::vector<double> step_times;                                   ///< [s] LrpimProblem::step_times
};

struct LrpimStatistics {
  int num_nodes = 0, num_constrained_nodes = 0;
  int num_volume_points = 0, num_reaction_points = 0, num_traction_points = 0, num_support_points = 0;
  long long matrix_entries = 0;     ///< stored entries of the tangent
  int factorisations = 0;           ///< or preconditioner set-ups (petsc_krylov)
  long long krylov_iterations = 0;  ///< petsc_krylov: iterations of all solves
  double min_rcond = 1.0;           ///< smallest rcond of G met while tabulating
  /// max over nodes of |int v n dA - int grad v dV| * r_q / int dV before the correction (0 for an exact
  /// rule)
  double divergence_defect = 0.0;
  /// set-up: the constructor's; assembly and solve: since the constructor or the last restart()
  double setup_seconds = 0.0, assembly_seconds = 0.0, solve_seconds = 0.0;
};

class LrpimModel {
 public:
  /// Tabulates the local quadrature and the RPIM functions of every point (throws SingularRpimMatrix or
  /// std::invalid_argument naming what to change).
  explicit LrpimModel(LrpimProblem problem);
  ~LrpimModel();

  /// Every step of problem().step_times; `on_step` (optional) is called after each converged step.
  /// @throws std::runtime_error when Newton does not converge in 25 iterations (names the step and residual)
  void run(const std::function<void(const LrpimModel&, const LrpimStepRecord&)>& on_step = {});

  /// Back to the undeformed body at t = 0 under a new load on the same traction faces, keeping the set-up (the
  /// tabulated local quadrature and RPIM functions, the tangent's pattern, the linear solver's ordering): the next
  /// run() gives what a model constructed with this load would, bit for bit, without the constructor's cost. This
  /// is how the Fig. 9 analogue solves one cloud for several forces (experiments::LoadSeries). The per-run
  /// statistics (assembly, solve, factorisations, Krylov iterations) and steps() start again from zero.
  /// @throws std::invalid_argument when the body has traction faces and load.traction is empty, or the step
  ///         times decrease
  void restart(LrpimLoad load);

  const LrpimProblem& problem() const { return problem_; }
  const LrpimStatistics& statistics() const { return statistics_; }
  const std::vector<LrpimStepRecord>& steps() const { return steps_; }
  /// 3 #nodes: the nodal displacements (RPIM interpolates, so these are u(X_i)) [m]
  const Eigen::VectorXd& nodal_displacements() const { return u_; }
  bool constrained(int node) const { return constrained_[node] != 0; }  ///< on a displacement face

  Eigen::Vector3d displacement_at(const Eigen::Vector3d& x) const;  ///< [m]
  core::Vector6 strain_at(const Eigen::Vector3d& x) const;          ///< engineering Voigt
  const RpimShapeFunctions& shape_functions() const { return rpim_; }
  const std::vector<LocalIntegrationPoint>& volume_points() const { return volume_; }
  /// Diagnostics: the local equations' tangent and residual at the current state for a step to `time` of length dt,
  /// without changing the model. With the balance imposed (LrpimProblem::balance_rigid_modes) Newton borders this
  /// system with the six balance equations and their multipliers, which are not in it.
  void linear_system(double time, double dt, LrpimMatrix* k, Eigen::VectorXd* r) const;
  /// Diagnostics: sets the nodal displacements (3 #nodes) [m].
  void set_nodal_displacements(const Eigen::VectorXd& u) { u_ = u; }
  /// The global balance at the current state and time (LrpimGlobalBalance).
  LrpimGlobalBalance global_balance() const;
  /// The correction that imposed it (LrpimProblem::balance_rigid_modes); inactive when it does not apply.
  LrpimBalanceCorrection balance_correction() const;
  /// d_i per node [m]: node_spacing, or each node's own (LrpimProblem::local_spacing)
  const std::vector<double>& node_spacings() const { return spacing_; }

 private:
  struct Solver;
  struct RigidBalance;
  /// The six balance equations (LrpimProblem::balance_rigid_modes), set up when they apply.
  void set_up_rigid_balance();
  /// The applied traction's net force and moment on the balance's rule, at load scale 1 (RigidBalance::applied).
  void integrate_balance_load();
  /// Calls at(condition, X, weight) at every point of the global balance's surface rule (degree 6 per triangle) on
  /// the traction and elastic-support faces: the rule of global_balance() and of the imposed balance alike.
  void for_each_balance_point(const std::function<void(FaceCondition, const Eigen::Vector3d&, double)>& at) const;
  /// R (and with k non-null the tangent's values, into the fixed pattern) at u_, time t with step dt; the
  /// points' new states into new_states. Parallel over test nodes (each owns its rows).
  void assemble(double time, double dt, LrpimMatrix* k, Eigen::VectorXd* r,
                std::vector<core::KelvinState>* new_states) const;
  void build_pattern();
  /// The condition of the faces labelled `label` (LrpimProblem::conditions; a label past its end is free).
  FaceCondition condition(int label) const {
    return label < static_cast<int>(problem_.conditions.size()) ? problem_.conditions[label]
                                                                : FaceCondition::free_surface;
  }

  LrpimProblem problem_;
  NodeSearch search_;
  std::vector<double> spacing_;  ///< d_i per node
  RpimShapeFunctions rpim_;
  core::KelvinLaw law_;
  /// per node: 1 on a displacement face. Bytes, not std::vector<bool>: the set-up writes it from many
  /// threads, and packed bits made neighbouring nodes' writes race (a lost mark left a clamped node with no
  /// equations).
  std::vector<std::uint8_t> constrained_;
  // Points node by node: node i's points of each kind are [begin[i], begin[i + 1]).
  std::vector<LocalIntegrationPoint> volume_;    ///< local sub-domains
  std::vector<LocalIntegrationPoint> reaction_;  ///< local boundaries on displacement faces
  std::vector<LocalIntegrationPoint> support_;   ///< local boundaries on elastic-support faces
  std::vector<LocalIntegrationPoint> traction_;  ///< local boundaries on traction faces (no trial functions)
  std::vector<int> volume_begin_, reaction_begin_, support_begin_, traction_begin_;
  std::vector<core::KelvinState> states_;  ///< volume points, then reaction points
  // The tangent's pattern: node i's row couples to columns_[row_begin_[i] .. row_begin_[i + 1]) (ascending
  // nodes), each a dense 3x3 block; entry (3i + a, 3 columns_[row_begin_[i] + k] + b) is value 9
  // row_begin_[i] + 3 a L_i + 3 k + b with L_i the row's length.
  std::vector<long long> row_begin_;
  std::vector<int> columns_;
  LrpimMatrix tangent_;
  std::unique_ptr<Solver> solver_;
  std::unique_ptr<RigidBalance> balance_;  ///< null when LrpimProblem::balance_rigid_modes does not apply
  Eigen::VectorXd u_;
  double time_ = 0.0;
  double constraint_scale_ = 0.0;
  std::vector<LrpimStepRecord> steps_;
  LrpimStatistics statistics_;
};

}  // namespace meshless::lrpim
