#pragma once
// The element-free Galerkin soft-tissue model of Zhang et al. 2020 §2: MLS shape functions (eqs. 1-8), the
// nonlinear Kelvin law (eqs. 9-13, core::KelvinLaw), incremental time stepping (eqs. 14-17, 20, 24) with a
// full Newton iteration per step on the consistent tangent, penalty essential BCs (eqs. 19, 23).
//
// Unknowns are the MLS nodal PARAMETERS U_i (not nodal displacements: MLS does not interpolate), so every
// displacement the model reports is u(X) = sum_i phi_i(X) U_i (eq. 7).
#include <Eigen/Core>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "core/inadmissible_strain.hpp"
#include "core/kelvin_law.hpp"
#include "core/step_cutback.hpp"
#include "meshless/efg/efg_problem.hpp"
#include "meshless/efg/integration_points.hpp"
#include "meshless/efg/nodal_sparsity.hpp"
#include "meshless/efg/penalty_boundary.hpp"
#include "meshless/solvers/anderson_acceleration.hpp"

namespace meshless {

class NodeSearch;
class SupportRadii;
class MlsShapeFunctions;
class CutWeights;
struct NodeHit;
class NodesWithNewEnrichment;
class EfgLinearSolver;

/// What happened in one time step.
struct StepRecord {
  int step = 0;             ///< 1-based
  double time = 0.0;        ///< t_{n+1} [s]
  double dt = 0.0;          ///< [s]
  double load_scale = 0.0;  ///< load_scale(time)
  int newton_iterations = 0;               ///< linear solves
  int linear_iterations = 0;               ///< Krylov iterations over the step (direct solver: GMRES on earlier factors)
  std::vector<double> residuals;           ///< ||R|| / ||F_ext|| before each solve and after the last
  double assembly_seconds = 0.0;
  double solve_seconds = 0.0;
  bool reused_factorisation = false;       ///< tangent unchanged (k = 0, same dt): factorisation reused
  int factorisations = 0;                  ///< prepare() calls (LU factorisations or preconditioner set-ups)
  int substeps = 1;                        ///< converged sub-steps (more than 1 after a cut-back)
  int cutbacks = 0;                        ///< halvings of the step
  std::vector<core::NewtonAttempt> failed_attempts;  ///< the Newton attempts that failed, in order
  /// Anderson-mixed updates that raised ||R|| and were replaced by the plain update (one residual each).
  int rejected_mixes = 0;
  /// Attempts with the predictor or Anderson mixing (EfgOptions) that failed and were retried plain, same step size.
  std::vector<core::NewtonAttempt> retried_plain;
  double admissibility_margin = 1.0;       ///< smallest 1 + 2k lambda over the volume points at convergence
};

struct EfgTimings {
  double setup_seconds = 0.0;            ///< node search, support radii, quadrature points, sparsity
  double shape_function_seconds = 0.0;   ///< MLS tabulation at every integration point (once)
  double assembly_seconds = 0.0;         ///< all steps
  double solve_seconds = 0.0;            ///< all steps (factorisation + back substitution)
};

/// What a local update of the cut did (EfgModel::advance_cut).
struct CutUpdate {
  int volume_points = 0, boundary_points = 0;  ///< after the update
  int volume_points_recomputed = 0;            ///< shape functions evaluated again (new or changed weights)
  int boundary_points_recomputed = 0;
  int modified_nodes = 0;                      ///< nodes whose weights the new cut modifies
  long long pairs_added = 0;  ///< node-pair blocks added to the kept sparsity pattern (0: the matrix storage stays)
  bool tables_packed = false;  ///< the shape-function tables ran out of spare slots and were packed (copied)
  double quadrature_seconds = 0.0;             ///< rebuilding the points, matching them, the reuse test, history
  double shape_function_seconds = 0.0;         ///< the MLS evaluations
  double coupling_seconds = 0.0;               ///< incidence, new node pairs, boundary terms, VCI
  double seconds = 0.0;                        ///< the whole update (quadrature, MLS, couplings, VCI)
};

/// Sizes for reports.
struct EfgStatistics {
  int num_nodes = 0;
  int num_cells = 0;
  int num_volume_points = 0;
  int num_boundary_points = 0;
  int num_lip_points = 0;             ///< boundary points on the lips of the cut (both sides)
  int num_cut_modified_nodes = 0;     ///< nodes whose weights the cut modifies (support meets the cut)
  double mean_nodes_per_point = 0.0;  ///< mean support size at the volume points
  long long matrix_nonzeros = 0;
  double alpha = 0.0;                 ///< penalty parameter [Pa/m] (an elastic support: its largest k_s)
  double penalised_area = 0.0, loaded_area = 0.0;  ///< [m^2]
  std::string linear_solver;
  /// The method behind linear_solver: direct, direct_umfpack, petsc_krylov or jacobi_bicgstab (never automatic).
  LinearSolverKind linear_solver_kind = LinearSolverKind::direct;
  /// Predicted cost of factorising this matrix (meshless/solvers/direct_solver_estimate.hpp; automatic solver choice
  /// only, 0 when not estimated).
  double direct_peak_memory_estimate = 0.0;  ///< [bytes]
  double direct_flops_estimate = 0.0;
  double available_memory = 0.0;  ///< [bytes] the budget the estimate was compared with (available_memory())
};

class EfgModel {
 public:
  EfgModel(EfgProblem problem, EfgOptions options = {});
  ~EfgModel();
  EfgModel(const EfgModel&) = delete;
  EfgModel& operator=(const EfgModel&) = delete;

  /// Called after every converged step that output_results() writes (step is 1-based).
  using StepObserver = std::function<void(const EfgModel& model, const StepRecord& step)>;

  /// The recipe: setup_system(); then per step: Newton (assemble_system(); solve();) and output_results().
  void run(const StepObserver& observer = {});

  /// Node search, support radii, MLS tabulation at volume and boundary points, VCI correction, sparsity,
  /// boundary terms, one KelvinState per volume point.
  void setup_system();
  /// Material update at every volume point for the current parameters U and time step, then the residual
  /// R = f_int + K^alpha U - alpha int phi u-bar - s(t) f_t (eq. 24) and, if with_matrix, the tangent
  /// K_n + K^alpha_n of eq. 20 with the consistent E_k (eq. 21).
  void assemble_system(bool with_matrix);
  /// *out = (K_n + K^alpha_n) v, the tangent of the last material update with its tangent (assemble_system(true),
  /// or a refresh on kept factors) applied to v without assembling it: the same sums as the matrix, point by point,
  /// at about the cost of a residual. GMRES on kept factors uses it, so that a refresh costs no assembly.
  void apply_tangent(const Eigen::VectorXd& v, Eigen::VectorXd* out);
  /// Solve (K_n + K^alpha_n) dU = -R (eq. 20) and update U (eq. 14). Throws if dU is not finite.
  /// @param tolerance  the relative residual a GMRES solve on earlier factors must reach (an inexact Newton step);
  ///                   0: EfgOptions::iterative_tolerance. A direct solve on current factors is exact either way.
  void solve(double tolerance = 0.0);
  /// Advance one step (1-based index into problem().step_times): Newton to convergence, then commit history.
  /// When Newton fails the step is halved and retried down to problem().min_step (core/step_cutback.hpp).
  /// @throws core::InadmissibleStrain when a converged state leaves the law's admissible range, or when the
  ///         smallest step fails after meeting an iterate outside it (core/step_cutback.hpp)
  /// @throws core::StepCutBackFailed when even the smallest step fails, with every attempt
  StepRecord solve_step(int step);
  /// Start again from the undeformed body (U = 0, fresh Kelvin history, no step records) under a new traction,
  /// keeping what setup_system() built (MLS tables, sparsity, penalty terms, solver choice) and the last
  /// factorised tangent, which solve_step() reuses while it still contracts the residual. Runs many loads on one
  /// node cloud (the surrogate's training, meshless/surrogate/surrogate_training.hpp) at the cost of the time steps alone.
  /// @param loaded_faces #boundary faces mask of the loaded faces (empty: the faces tagged load)
  /// @param traction t-bar [Pa] at full load on those faces (eq. 24), scaled by problem().load_scale
  /// @param keep_factors false: forget the factorised tangent too, so that the run equals a new model's bit for bit
  ///        (its first step factorises, as a new model's does; the Fig. 9 analogue's series, as the LRPIM's)
  void restart(std::vector<char> loaded_faces, VectorField traction, bool keep_factors = true);
  /// Replace the cut by `cut` (a progressive incision: the cut advanced) after setup_system(), keeping the
  /// history. A local update (paper §4): the quadrature is rebuilt (cheap geometry), but only the points that are
  /// new or whose covering nodes change weight get their shape functions evaluated again; the others keep their
  /// rows. Points of a cell that is split differently take the history of the nearest old point of that cell.
  /// The sparsity pattern and the linear solver's choice are kept: a longer cut mostly removes couplings, and
  /// the few node pairs that only the new points couple are added (NodalSparsity::add_pairs). The matrix may
  /// therefore hold pairs the cut has since uncoupled, assembled as zeros. The next solve prepares the solver
  /// again. Gives the same tables, and the same stiffness values, as a set-up with `cut` from the start, to
  /// round-off.
  CutUpdate advance_cut(const core::RuledSurface& cut);
  /// After setup_system(): go on from the converged state of `earlier`, a model of the same node cloud and
  /// background cells whose cut may differ. Takes its nodal parameters U and carries the history of its volume
  /// points onto this model's points as advance_cut() does (the same point keeps its state; a point of a cell split
  /// differently takes the state of the nearest old point of that cell). A full set-up that continues where another
  /// model stopped: the reference a local update of the cut is compared with (tests/test_efg_cut.cpp).
  /// @throws std::invalid_argument when the node clouds or the cells differ
  void continue_from(const EfgModel& earlier);

  // --- results ---------------------------------------------------------------------------------------------
  /// u(X) = sum_i phi_i(X) U_i (eq. 7) at arbitrary material points, #points by 3 [m]. A point next to the cut
  /// is evaluated on the lip core::RuledSurface::side assigns to it (the rule the FEM reference uses too).
  core::PointMatrix displacements_at(const core::PointMatrix& points) const;
  /// One point; `side` (+1 / -1) evaluates a point on the cut as the limit from that lip, 0 applies the rule.
  Eigen::Vector3d displacement_at(const Eigen::Vector3d& x, int side = 0) const;
  /// Displacement at the node positions (interpolated, not the parameters).
  core::PointMatrix nodal_displacements() const { return displacements_at(nodes()); }
  const Eigen::VectorXd& nodal_parameters() const { return u_; }  ///< 3N, the U_i
  const core::PointMatrix& nodes() const { return problem_.mesh.vertices; }
  /// Total engineering strain at every volume point (standard MLS gradients, eq. 17/22).
  std::vector<core::Vector6> quadrature_strains() const;
  const ShapeTable& volume_points() const { return volume_; }
  const ShapeTable& boundary_points() const { return surface_; }
  const std::vector<core::KelvinState>& states() const { return states_; }

  const EfgProblem& problem() const { return problem_; }
  const EfgOptions& options() const { return options_; }
  const std::vector<StepRecord>& steps() const { return records_; }
  const EfgTimings& timings() const { return timings_; }
  /// The smallest 1 + 2k lambda over the converged steps so far, and where (docs/MATERIAL.md §1.5).
  const core::SmallestMargin& smallest_margin() const { return smallest_margin_; }
  const EfgStatistics& statistics() const { return stats_; }
  const MlsShapeFunctions& shape_functions() const { return *mls_; }
  /// The cut's weight modifier, or null for an uncut body.
  const CutWeights* cut_weights() const { return cut_weights_.get(); }
  /// The system matrix of the last assemble_system(true) (tangent + penalty, eq. 20).
  const SparseMatrix& system_matrix() const { return matrix_; }
  /// Its node-pair pattern (after setup_system()).
  const NodalSparsity& sparsity() const { return *sparsity_; }
  double alpha() const { return alpha_; }
  double residual_norm() const { return residual_.norm(); }
  /// Largest |sum_i int grad phi_i - oint phi_i n| over nodes before the VCI correction [m^2] (diagnostic).
  double divergence_defect() const { return divergence_defect_; }

 private:
  void update_material(double dt, bool with_tangent);
  /// residual_ = the internal forces, eq. 21's int B_i^T sigma at the current stresses (update_material first).
  void add_internal_forces();
  /// u(X_q) = sum_j phi_j(X_q) u_j at every surface point that carries the penalty (eq. 23); zero at the others.
  std::vector<Eigen::Vector3d> penalised_surface_values(const Eigen::VectorXd& u) const;
  /// *out = sum_q B_i(X_q)^T weighted_q per node i (test gradients with VCI), point by point.
  void add_test_gradient_sums(const std::vector<core::Vector6>& weighted, Eigen::VectorXd* out);
  /// The last material update's weakest point as an error when it is outside the admissible range, else null.
  std::shared_ptr<const core::InadmissibleStrain> inadmissible_iterate() const;
  /// One Newton solve from the committed state at t_from to t_to; commits the history when it converges and
  /// restores the parameters U when it fails (the attempt callback of core::advance_with_cutback).
  core::NewtonAttempt newton_step(double t_from, double t_to, StepRecord* record);
  /// Newton from the current U (u_start: the committed state, restored on failure) to equilibrium at t_to, without
  /// committing; `accelerated` mixes the updates on kept factors (EfgOptions::anderson_depth).
  core::NewtonAttempt newton_iterations(double t_from, double t_to, const Eigen::VectorXd& u_start, bool accelerated,
                                        StepRecord* record);
  /// Move U to the extrapolated start of the step (EfgOptions::extrapolate_start) when the last converged
  /// (sub-)step ended at t_from and the load kept its rate; false (U unchanged) otherwise.
  bool predict_start(double t_from, double t_to);
  /// The relative residual a GMRES solve on earlier factors must reach at Newton's relative residual
  /// `relative_residual`, when Newton's tolerance is `target_over_residual` times ||R|| (EfgOptions::gmres_forcing).
  double gmres_tolerance(double relative_residual, double target_over_residual) const;
  /// Build the weight modifier of `cut` (null: none) and install it into the MLS shape functions.
  void install_cut(const core::RuledSurface* cut);
  /// Volume points, and boundary points (outer faces and the lips of the cut), for the current problem.
  void build_quadrature(QuadraturePoints* volume, QuadraturePoints* surface) const;
  /// Everything that follows from the tabulated points and their incidence (the caller builds it): sparsity,
  /// boundary terms, VCI, statistics.
  /// Without new_pattern the sparsity pattern, the matrix storage and the linear solver's choice stay as they
  /// are: the caller made sure the pattern holds every node pair of the tables, and brought the VCI sums (defect_,
  /// support_volume_) up to date with the rows it changed (advance_cut).
  void build_couplings(bool new_pattern);
  /// True when a node covering x has a different weight (or gradient) under `before` than under the current cut.
  /// With `enrichment` (both cuts enriched alike) the test searches only the nodes modified by either cut, and
  /// compares Phi where one of them covers x; otherwise it evaluates every covering node.
  bool weights_changed(const CutWeights* before, const Eigen::Vector3d& x, int side, bool gradients,
                       std::vector<NodeHit>* hits, const NodesWithNewEnrichment* enrichment) const;

  EfgProblem problem_;
  EfgOptions options_;
  core::KelvinLaw law_;
  double alpha_ = 0.0;

  std::unique_ptr<NodeSearch> search_;
  std::unique_ptr<SupportRadii> radii_;
  std::unique_ptr<MlsShapeFunctions> mls_;
  std::unique_ptr<CutWeights> cut_weights_;
  ShapeTable volume_, surface_;
  NodeIncidence volume_incidence_, surface_incidence_;
  // The arrays of the incidences before the last local update of the cut, reused by the next (advance_cut).
  NodeIncidence spare_volume_incidence_, spare_surface_incidence_;
  std::unique_ptr<NodalSparsity> sparsity_;
  BoundaryTerms boundary_;
  Eigen::Matrix3Xd vci_correction_;  // 3 by N, xi_i added to test-function gradients
  // The sums behind it: oint phi_i n - int grad phi_i [m^2] and int_{supp i} 1 [m^3], per node; kept so that a local
  // update of the cut corrects them by the rows it changes.
  Eigen::Matrix3Xd defect_;
  Eigen::VectorXd support_volume_;
  double divergence_defect_ = 0.0;

  std::vector<core::KelvinState> states_;   // history at t_n, one per volume point
  std::vector<core::Vector6> strain_, stress_;
  std::vector<core::Matrix6> tangent_;
  Eigen::MatrixXd force_blocks_;  // 3N by blocks: scratch of add_test_gradient_sums, kept to spare its allocation
  std::vector<core::Vector6> weighted_stress_;  // per volume point: scratch of the same
  // The refreshed tangent of this iterate is in tangent_ (per point), not in matrix_: solve() applies it point by
  // point (apply_tangent) and assembles matrix_ only if it has to factorise.
  bool tangent_by_points_ = false;

  Eigen::VectorXd u_, residual_, external_;
  SparseMatrix matrix_;
  std::unique_ptr<EfgLinearSolver> linear_solver_;  // created by setup_system for the sparsity pattern
  double current_dt_ = 0.0;
  double current_time_ = 0.0;     // t_{n+1} of the (sub-)step being solved, for messages
  std::vector<double> margins_;   // 1 + 2k lambda_min at each volume point of the current iterate
  int weakest_point_ = -1;        // the volume point with the smallest margin (-1: k = 0, not computed)
  core::SmallestMargin smallest_margin_;
  double factorised_dt_ = -1.0;
  // The start and interval of the last converged (sub-)step, for predict_start; reset when U starts afresh or the
  // cut changes the shape functions.
  struct PreviousStep {
    Eigen::VectorXd u;
    double t_from = 0.0, t_to = 0.0;
  };
  std::optional<PreviousStep> previous_start_;
  // Anderson mixing of the updates on the kept factors, its secant pairs kept from step to step while the factors
  // stay; reset with previous_start_ and whenever the factors change.
  AndersonAcceleration mixing_;
  int last_linear_iterations_ = 0;    // Krylov iterations of the last solve() (0: a back-substitution alone)
  bool last_solve_prepared_ = false;  // the last solve() factorised (or set up the preconditioner)
  bool matrix_current_ = false;  // matrix_ matches the current iterate

  std::vector<StepRecord> records_;
  EfgTimings timings_;
  EfgStatistics stats_;
  bool set_up_ = false;
};

}  // namespace meshless
