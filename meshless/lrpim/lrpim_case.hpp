#pragma once
// The LRPIM model on a load case (core::Case + core::Geometry): the body is the node cloud's boundary surface
// (Geometry::meshless_mesh: its vertices are the nodes, its boundary triangles carry core::FaceTag free/fixed/load),
// and the case's load, support, material and times are translated as the EFG's problem_from_case does
// (meshless/efg/efg_problem.cpp): core::load_program for the traction (force / this mesh's load-patch area), the ramp
// and the step times; core::FixedRegionSpec::support_stiffness for an elastic support (a Robin term); a clamp as
// u = 0 at the nodes on fixed faces. docs/LRPIM.md §3 and §5.
//
// Units: SI throughout (m, Pa, s). Thread safety: run_lrpim_case uses OpenMP inside; call it from one thread.
// With LrpimLinearSolver::mumps (the default here), MPI must be initialised (tissue's main and the MPI test mains do).
#include <functional>
#include <nlohmann/json.hpp>
#include <vector>

#include "core/case.hpp"
#include "core/geometry.hpp"
#include "meshless/lrpim/lrpim_model.hpp"
#include "meshless/lrpim/lrpim_problem.hpp"

namespace meshless::lrpim {

/// One converged time step of a case run.
struct LrpimStepReport {
  int step = 0;       ///< 1-based
  double time = 0.0;  ///< [s]
  double wall_seconds = 0.0, assembly_seconds = 0.0, solve_seconds = 0.0;  ///< solve: factorisations + solves
  int newton_iterations = 0;
  int factorisations = 0;
  std::vector<double> residuals;  ///< ||R|| / reference per iteration (LrpimProblem::newton_tolerance)
  int rejected_mixes = 0;         ///< LrpimStepRecord::rejected_mixes
};

struct LrpimCaseOptions {
  /// 6 polar x 12 azimuthal x 4 radial (up to 576 points per node; the verification rule is 8 x 16 x 4). With the
  /// body's balance imposed (balance_rigid_modes) the CI-sized lung's RMSE against the FEM is 2.80 / 1.90 / 2.07 /
  /// 2.02 % of the peak for 4 x 8 x 3, this rule, 8 x 16 x 4 and 10 x 20 x 4, and lung_small's 1.13 % here against
  /// 0.81 % at 8 x 16 x 4 (0.014 mm apart, below the reference's bar of 0.031 mm) for 60 % of the time and 66 % of
  /// the memory (docs/LRPIM.md §5).
  LocalQuadratureRule rule = {4, 6, 12};
  double alpha_q = 1.5;  ///< r_q / node spacing
  /// LrpimProblem::local_spacing: on for case runs, whose clouds are graded (the lung's is refined ~2x near the load
  /// and the support); docs/LRPIM.md §5 gives what it changed on the lung.
  bool local_spacing = true;
  RpimParameters rpim;   ///< the literature's MQ (q 1.03, alpha_c 4, 20 nodes)
  LrpimLinearSolver linear_solver = LrpimLinearSolver::mumps;
  std::string krylov_options = LrpimProblem{}.krylov_options;  ///< petsc_krylov only
  double newton_tolerance = 1e-8;     ///< as the EFG's EfgOptions::newton_tolerance
  double refactor_contraction = 0.2;  ///< modified Newton by the EFG's rule (LrpimProblem::refactor_contraction)
  int max_newton_iterations = 25;
  bool divergence_correction = true;  ///< LrpimProblem::divergence_correction
  LrpimTestFunction test_function = LrpimTestFunction::shepard;  ///< LrpimProblem::test_function
  bool balance_rigid_modes = true;  ///< LrpimProblem::balance_rigid_modes
  /// Nodes of the cloud closer than this times the case's node spacing to a node kept before them (in the cloud's
  /// order) are left out of the LRPIM's nodes; 0 keeps all. The RPIM interpolates every node it is given, and nodes
  /// far closer than the spacing (where a region's imprint cuts an STL face near its corner) make nearly equal MQ
  /// rows (docs/LRPIM.md §6). The body's surface and the samples are unchanged.
  double min_node_separation = 0.0;
  /// Called after each converged step (optional).
  std::function<void(const LrpimStepReport&)> on_step;
};

struct LrpimCaseRun {
  Eigen::MatrixXd sample_displacements;  ///< #samples by 3 [m], at Geometry::sample_points, after the last step
  double setup_seconds = 0.0;            ///< tabulation of the local quadrature and the RPIM functions, pattern
  std::vector<LrpimStepReport> steps;
  int n_nodes = 0, n_dofs = 0;
  /// What was run and measured: parameters, point counts, tangent entries, smallest rcond, divergence defect,
  /// load-patch area, traction and total force, factorisations, time split, peak resident memory.
  nlohmann::json details;
};

/// The case as an LRPIM problem (no solve). Throws core::CaseError at /cut for a cut case (the LRPIM model has no
/// crack treatment), and what core::load_program throws (no load face on the cloud).
LrpimProblem lrpim_problem_from_case(const core::Case& c, const core::Geometry& g, const LrpimCaseOptions& options = {});

/// The case's load on this geometry's cloud (core::load_program: the traction is the force over the cloud's
/// load-patch area; the ramp; the step times), as LrpimModel::restart takes it. lrpim_problem_from_case uses it too.
LrpimLoad lrpim_load_from_case(const core::Case& c, const core::Geometry& g);

/// Runs `model` through its steps and reads the samples and the diagnostics. The model must have been built from
/// lrpim_problem_from_case(c, g, ...), or since restarted under lrpim_load_from_case(c, g) for a case that differs
/// from that one only in its load. run.setup_seconds is the model's constructor time, whether or not this run paid
/// it. `on_step` (optional) as LrpimCaseOptions::on_step.
LrpimCaseRun run_lrpim_model(LrpimModel& model, const core::Case& c, const core::Geometry& g,
                             const std::function<void(const LrpimStepReport&)>& on_step = {});

/// Sets up and runs the case through all of its steps; the samples are the RPIM interpolation of the nodal
/// solution at g.sample_points. Throws core::CaseError (see above), SingularRpimMatrix, core::InadmissibleStrain,
/// std::runtime_error (Newton did not converge: the message names the step).
LrpimCaseRun run_lrpim_case(const core::Case& c, const core::Geometry& g, const LrpimCaseOptions& options = {});

}  // namespace meshless::lrpim
