#pragma once
// The boundary-value problem the FEM reference solves, without any deal.II type, so that experiments,
// tests and benchmarks can describe a problem without compiling deal.II headers.
//
// Small-strain quasi-static equilibrium (paper eq. 17–21) with the shared Kelvin law (core/kelvin_law.hpp),
// stepped in time through the one-internal-variable recursion of eqs. 11–13.
#include <Eigen/Core>
#include <array>
#include <functional>
#include <vector>

#include "core/kelvin_law.hpp"
#include "core/step_cutback.hpp"
#include "core/tet_mesh.hpp"

namespace reference_fem {

/// Boundary ids on the deal.II triangulation. The first four equal core::FaceTag so that a case mesh
/// carries its tags straight into deal.II; verification problems use their own ids above them.
namespace boundary_id {
constexpr unsigned int free_surface = static_cast<unsigned int>(core::FaceTag::free_surface);
constexpr unsigned int fixed = static_cast<unsigned int>(core::FaceTag::fixed);
constexpr unsigned int load = static_cast<unsigned int>(core::FaceTag::load);
constexpr unsigned int crack = static_cast<unsigned int>(core::FaceTag::crack);
}  // namespace boundary_id

/// A time scaling of a boundary value: value(t) = scale(t) * value. Empty means 1 for all t.
using TimeScale = std::function<double(double)>;

/// A field over space and time (x [m], t [s]) -> vector, for non-uniform boundary data.
using VectorField = std::function<Eigen::Vector3d(const Eigen::Vector3d&, double)>;

/// Prescribed displacement u_c = scale(t) * value_c on the components c with components[c] == true.
/// When `field` is set it replaces scale * value (used by the cantilever verification).
struct DirichletCondition {
  unsigned int boundary_id = boundary_id::fixed;
  std::array<bool, 3> components{{true, true, true}};
  Eigen::Vector3d value = Eigen::Vector3d::Zero();  ///< [m]
  TimeScale scale;
  VectorField field;
};

/// Traction t = scale(t) * traction [Pa] on every face with the boundary id (uniform: the load patch).
/// When `field` is set it replaces scale * traction.
struct TractionCondition {
  unsigned int boundary_id = boundary_id::load;
  Eigen::Vector3d traction = Eigen::Vector3d::Zero();  ///< [Pa]
  TimeScale scale;
  VectorField field;
};

/// Elastic (Robin) support: traction t = -stiffness(x) u [Pa] on every face with the boundary id, a spring bed
/// standing for the tissue that holds the organ (core::FixedRegionSpec, support "elastic"). It adds
/// int k_s phi_i . phi_j dA to the tangent and int k_s u . phi_i dA to the internal force, so the support's
/// reactions are part of the internal force as a clamp's are.
struct ElasticSupportCondition {
  unsigned int boundary_id = boundary_id::fixed;
  std::function<double(const Eigen::Vector3d&)> stiffness;  ///< k_s(x) [Pa/m], x [m]
};

struct BoundaryConditions {
  std::vector<DirichletCondition> dirichlet;
  std::vector<TractionCondition> tractions;
  std::vector<ElasticSupportCondition> supports;
};

/// How each Newton system K du = R (K = the consistent tangent, non-symmetric when k != 0) is solved.
/// Both are right-preconditioned GMRES on the exact tangent, so Newton converges as with an exact solve;
/// they differ in the preconditioner, which may come from an earlier tangent (rebuilt when GMRES slows down).
enum class LinearSolverType {
  /// Algebraic multigrid: Trilinos ML smoothed aggregation with the six rigid-body modes as its near null
  /// space. Memory and time grow about linearly with the DOFs; runs on any number of MPI processes.
  amg,
  /// The UMFPACK LU factors of an earlier tangent. Fastest for small problems (a few thousand DOFs), but
  /// the 3-D fill-in makes it grow like DOFs^1.5-2 in time and memory. One MPI process only.
  direct,
};

/// The linear solver of the Newton systems: GMRES on the exact tangent, right-preconditioned (the true residual
/// is measured). Defaults per type: for_type().
struct LinearSolverParameters {
  LinearSolverType type = LinearSolverType::amg;
  /// GMRES stops at eta_k ||R_k||, eta_k = max(tolerance, min(0.1, forcing * r_k)), r_k the relative Newton
  /// residual (inexact Newton with a quadratic forcing term, Eisenstat & Walker 1996): far from the solution a
  /// rough solve does as well as an exact one, and near it eta_k r_k ~ r_k^2 keeps Newton quadratic.
  /// forcing = 0, or a linear material (k = 0): always `tolerance`.
  double tolerance = 1e-10;
  double forcing = 0.1;  ///< 0.01 before the extrapolated start made r_k small (docs/FEM_REFERENCE.md)
  int max_iterations = 500;
  /// Rebuild the preconditioner (LU factors or AMG hierarchy) from the current tangent when the previous
  /// GMRES solve needed more than this many iterations per decade of residual reduction (a stale
  /// preconditioner converges more slowly).
  double rebuild_after = 8.0;

  /// The defaults of each type.
  static LinearSolverParameters for_type(LinearSolverType type);
};

inline LinearSolverParameters LinearSolverParameters::for_type(LinearSolverType type) {
  LinearSolverParameters p;
  p.type = type;
  if (type == LinearSolverType::direct) {
    // LU factors of a nearby tangent need a few iterations for all 12 decades; refactor beyond 15.
    p.tolerance = 1e-12;
    p.forcing = 0.0;
    p.max_iterations = 200;
    p.rebuild_after = 15.0 / 12.0;
  }
  return p;
}

/// Newton's method on the residual of eq. 21 with the consistent tangent of the Kelvin law.
struct NewtonParameters {
  double tolerance = 1e-8;  ///< on ||R|| / max(||R_0||, ||F_ext||, ||F_int||), constrained rows excluded
  int max_iterations = 25;
  LinearSolverParameters linear;
  /// When Newton fails on a step, the step is halved and retried down to this size [s]
  /// (core/step_cutback.hpp); 0 disables the cut-back.
  double min_step = 0.0;
  /// Start each step from U_n + (dt_{n+1} / dt_n)(U_n - U_{n-1}) instead of U_n while every boundary condition keeps
  /// its rate (core/step_predictor.hpp, the rule the meshless models use). Changes the path only: the converged
  /// answer is the same to the Newton tolerance; a failed predicted attempt is retried from U_n before a cut-back.
  bool extrapolate_start = true;
  /// Assemble the residual alone, without the tangent, where Newton's contraction predicts that the update just
  /// solved ends the step (ViscoelasticSolver::assemble_system): that assembly only confirms convergence. The answer is
  /// the same to the bit; when the prediction misses, the tangent of that iterate is assembled before the solve.
  bool confirm_without_tangent = true;
};

struct SolverParameters {
  core::KelvinParameters material;
  int degree = 2;          ///< FE_SimplexP degree (QGaussSimplex with degree+1 points per direction)
  NewtonParameters newton;
  /// WorkStream assembly threads per MPI process; 0 keeps deal.II's choice (the node's cores divided
  /// among the MPI processes on it, set by Utilities::MPI::MPI_InitFinalize).
  unsigned int threads = 0;
};

/// What one time step did (reported per step in timings.json).
struct StepReport {
  int step = 0;               ///< 1-based
  double time = 0.0;          ///< t_{n+1} [s]
  int newton_iterations = 0;  ///< number of linear solves
  int linear_iterations = 0;  ///< GMRES iterations over the step
  int preconditioner_builds = 0;  ///< LU factorizations or AMG set-ups during the step
  std::vector<double> residuals;  ///< relative residual before each solve, then the converged one
  /// Assemblies of the residual with the tangent, and of the residual alone (the last one of a step, when Newton's
  /// contraction predicts that it ends the step: ViscoelasticSolver::assemble_system).
  int tangent_assemblies = 0;
  int residual_only_assemblies = 0;
  double assembly_seconds = 0.0;  ///< both kinds
  double solve_seconds = 0.0;
  double wall_seconds = 0.0;
  int substeps = 1;                                  ///< converged sub-steps (more than 1 after a cut-back)
  std::vector<core::NewtonAttempt> failed_attempts;  ///< Newton attempts that failed and were cut back
  /// Attempts from the extrapolated start that failed and were retried from the committed state (no cut-back).
  std::vector<core::NewtonAttempt> retried_plain;
  double admissibility_margin = 1.0;  ///< smallest 1 + 2k lambda over the quadrature points at convergence
};

/// Strain in a ball around a point (e.g. under the probe), from the converged quadrature-point history.
/// The measure is the largest absolute principal strain, |eps|_max = max_i |lambda_i(eps)|.
struct BallStrain {
  double mean = 0.0;    ///< volume average of |eps|_max over the quadrature points in the ball
  double peak = 0.0;    ///< largest |eps|_max at one quadrature point in the ball
  double volume = 0.0;  ///< [m^3] the quadrature weight found in the ball (0: no point inside)
};

}  // namespace reference_fem
