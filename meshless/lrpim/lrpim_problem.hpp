#pragma once
// What the LRPIM model solves: a node cloud in a body given by its closed boundary surface, a boundary condition per
// triangle label, the Kelvin law and the step times (docs/LRPIM.md). The same problem class as the EFG's
// (meshless/efg/efg_problem.hpp), without the background mesh: only the nodes and the boundary triangles are used.
// A box (the verification problems) is SurfaceBody::from_box, whose labels are the faces -x +x -y +y -z +z; a load
// case's body (meshless/lrpim/lrpim_case.hpp) is the node cloud's boundary, labelled by core::FaceTag.
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/kelvin_law.hpp"
#include "core/tet_mesh.hpp"
#include "meshless/lrpim/local_quadrature.hpp"
#include "meshless/lrpim/rpim_shape_functions.hpp"
#include "meshless/lrpim/surface_body.hpp"

namespace meshless::lrpim {

/// The condition on the triangles of one label.
enum class FaceCondition {
  free_surface,     ///< t = 0: no term (the natural condition)
  traction,         ///< t = load_scale(t) * traction(X), through the local boundary integral
  displacement,     ///< u = prescribed_displacement(X): the nodes on these triangles get their values directly
                    ///< (Kronecker delta), and the unknown reaction sigma n is integrated on the local boundary of
                    ///< the nodes whose sphere reaches them
  elastic_support,  ///< t = -support_stiffness(X) u (a Robin term, core::FixedRegionSpec's elastic support): a
                    ///< natural condition, integrated on the local boundary like a traction, no node constrained
};

/// The linear solver of each Newton iteration (the tangent is not symmetric).
enum class LrpimLinearSolver {
  sparse_lu,  ///< Eigen::SparseLU (COLAMD), no MPI needed: the small verification problems
  mumps,      ///< MUMPS sparse LU with METIS (meshless/solvers/mumps_lu.hpp); needs MPI initialised
  petsc_krylov,  ///< a PETSc Krylov method (LrpimProblem::krylov_options, meshless/solvers/petsc_krylov_solver.hpp)
                 ///< whose preconditioner is built once per "factorisation"; needs PETSc initialised
};

/// The test function v_i of node i's local equations; each vanishes on node i's sphere (radius r_q,i), so every
/// choice keeps the weak form local. What differs is what the sum of all local equations is (docs/LRPIM.md §5):
enum class LrpimTestFunction {
  /// The cubic spline w_i(|X - X_i| / r_q,i) (Atluri's MLPG1, Liu & Gu's LRPIM). The v_i do not sum to 1, so the sum
  /// of the local equations is not the body's balance: on the lung the internal forces carried ~20 % of the load.
  spline,
  /// Shepard-normalised, w_i / sum_j w_j over the spheres that cover X: the v_i sum to 1, so with exact
  /// integration the net force balances; the net moment need not (they do not reproduce linear fields).
  shepard,
  /// The first-order MLS functions of the spheres' splines (meshless/mls/mls_shape_functions.hpp with radii r_q,j):
  /// sum_i v_i = 1 and sum_i v_i X_i = X, so with exact integration the sum of the local equations tested against
  /// any rigid motion is the body's force and moment balance, as in a Galerkin method.
  mls,
};

struct LrpimProblem {
  std::string name = "lrpim";
  core::PointMatrix nodes;  ///< #nodes by 3 [m], inside the body or on its surface (to 1e-9 of the spacing)
  std::optional<SurfaceBody> body;
  /// The condition of each triangle label (SurfaceBody::label); labels beyond the vector's end are free.
  std::vector<FaceCondition> conditions;
  std::function<Eigen::Vector3d(const Eigen::Vector3d&)> prescribed_displacement;  ///< [m], held in time
  std::function<Eigen::Vector3d(const Eigen::Vector3d&)> traction;                 ///< [Pa] at full load
  std::function<double(const Eigen::Vector3d&)> support_stiffness;                 ///< k_s [Pa/m]
  std::function<double(double)> load_scale;  ///< factor on the traction at time t; empty: 1 (a step load)
  core::KelvinParameters material;
  /// Times of the steps [s]. The first step goes from t = 0 to step_times[0]; step_times[0] = 0 is the
  /// instantaneous (dt = 0) elastic step, as in the EFG and FEM models.
  std::vector<double> step_times = {0.0};
  double node_spacing = 0.0;  ///< d_c [m]: scales the MQ shape parameter and r_q
  RpimParameters rpim;
  double alpha_q = 1.5;  ///< r_q = alpha_q * node_spacing, the radius of each node's local sub-domain
  /// false: d_c = node_spacing everywhere (uniform clouds: the verification problems). true: each node's own
  /// spacing d_i, the mean distance to its 6 nearest nodes (h on a cubic grid's interior), sets its sub-domain
  /// r_q,i = alpha_q d_i, and d_c at a point is the mean d_i of its support (RpimShapeFunctions::set_node_spacing):
  /// Liu & Gu define both by the local nodal spacing, which a graded cloud (the lung's, refined 2x near the load
  /// and the support) does not have uniform (docs/LRPIM.md §5).
  bool local_spacing = false;
  LocalQuadratureRule rule;
  /// Correct each node's test gradient by a constant so that the local divergence identity
  /// int_{Omega_s} grad v dV = int_{boundary of Omega_s in dOmega} v n dA holds for the quadrature (the linear
  /// variationally consistent correction of Chen, Hillman & Rueter 2013, which the EFG applies to its test
  /// functions, here per local domain). Without it the clipped spheres' angular quadrature error breaks the
  /// patch test at ~1e-3 (docs/LRPIM.md §4).
  bool divergence_correction = true;
  /// The test function of each node's local equations (LrpimTestFunction).
  LrpimTestFunction test_function = LrpimTestFunction::shepard;
  /// When the body is held by elastic supports alone (no displacement face), its rigid motion is set by the six
  /// global balance equations: the support's reaction must cancel the applied traction's net force and moment. A
  /// Galerkin method satisfies them by construction; MLPG's local equations only to their quadrature's error, and on
  /// the lung that error turned the body too little (docs/LRPIM.md §5). true: impose the six equations exactly, with
  /// six multipliers lambda that scale a fictitious body force b(X) = lambda_F + lambda_M x (X - X_c) / L added to
  /// every local equation (a bordered system). lambda is then the quadrature's imbalance, reported by
  /// LrpimModel::balance_correction(); it vanishes where the local equations already balance. Ignored when a face
  /// is a displacement face (the constraint holds the rigid modes) or no face is an elastic support.
  bool balance_rigid_modes = true;

  /// Newton stops when ||R|| <= newton_tolerance * max(||external force at full load||, ||R|| at the step's start).
  double newton_tolerance = 1e-10;
  int max_newton_iterations = 25;
  /// 0: full Newton (the tangent factorised at every iteration). > 0: the last factors are reused while the updates
  /// on them in this step reduce ||R|| to at most this ratio per update on average (the geometric mean, since
  /// Anderson-mixed updates contract unevenly) and would reach the tolerance within max_newton_iterations, and the
  /// current tangent is factorised when they do not (meshless/solvers/kept_factors.hpp): a nearly linear case
  /// then factorises once or twice per run.
  double refactor_contraction = 0.0;
  /// With kept factors (refactor_contraction > 0): Anderson mixing of the updates on one set of factors, and the
  /// extrapolated start of each step while the load keeps its rate; the EFG's EfgOptions::anderson_depth and
  /// extrapolate_start (docs/MESHLESS.md §2). Change the path to equilibrium, never the equilibrium. 0 / false: off.
  int anderson_depth = 5;
  bool extrapolate_start = true;
  LrpimLinearSolver linear_solver = LrpimLinearSolver::sparse_lu;
  /// petsc_krylov: PETSc options and the relative tolerance of each solve (Newton's own test decides convergence).
  std::string krylov_options = "-ksp_type gmres -ksp_gmres_restart 200 -pc_type ilu";
  double krylov_tolerance = 1e-9;
};

}  // namespace meshless::lrpim
