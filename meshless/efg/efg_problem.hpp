#pragma once
// What the EFG model solves, independent of where it comes from: the lung case of a config file
// (problem_from_case) or a verification problem built in code (patch test, cantilever, creep bar).
#include <Eigen/Core>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/case.hpp"
#include "core/geometry.hpp"
#include "core/kelvin_law.hpp"
#include "core/ruled_surface.hpp"
#include "core/tet_mesh.hpp"
#include "meshless/cut/cut_weights.hpp"
#include "meshless/mls/support_radii.hpp"

namespace meshless {

using VectorField = std::function<Eigen::Vector3d(const Eigen::Vector3d& x)>;
/// A traction on a cut's lips [Pa] from the point [m] and the lip's outward unit normal.
using LipTraction = std::function<Eigen::Vector3d(const Eigen::Vector3d& x, const Eigen::Vector3d& outward_normal)>;

enum class LinearSolverKind {
  automatic,        ///< direct when the estimated peak memory of the LU fits the available memory, else petsc_krylov
  direct,           ///< MUMPS sparse LU (meshless/solvers/mumps_lu.hpp); works for the non-symmetric tangent; needs MPI initialised
  direct_umfpack,   ///< UMFPACK sparse LU, the earlier direct solver (kept for comparison: 1.7x slower on the lung)
  petsc_krylov,     ///< a PETSc Krylov method and preconditioner (EfgOptions::krylov_options); needs PETSc initialised
  jacobi_bicgstab,  ///< Eigen::BiCGSTAB with a Jacobi preconditioner (the earlier fallback, kept for comparison)
};

/// The petsc_krylov options that were EfgOptions::krylov_options before SSOR by Eisenstat's trick: Trilinos ML with
/// twenty GCR iterations (each preconditioned by SOR) smoothing every level, under FGMRES(200) because that smoother
/// is not a fixed linear operator. Built from the tangent's sparser copy (preconditioner_drop_tolerance 0.01), it is
/// the comparison of bench_efg's BM_EfgSolveMlGcr and of the solver tests.
inline constexpr const char* kMlWithGcrSmoothersOptions =
    "-ksp_type fgmres -ksp_gmres_restart 200 -pc_type ml -mg_levels_ksp_type gcr -mg_levels_ksp_max_it 20 "
    "-mg_levels_pc_type sor";

/// Solver knobs with defaults; see docs/MESHLESS.md for the reasons behind each.
struct EfgOptions {
  double newton_tolerance = 1e-8;  ///< ||R|| <= tol * ||external force|| (eq. 24 residual)
  int max_newton_iterations = 25;
  /// Keep the factorised tangent while each iteration reduces ||R|| by at least this ratio and that rate reaches
  /// newton_tolerance within max_newton_iterations; refresh the tangent otherwise (k != 0). 0 gives full Newton
  /// (a fresh tangent every iteration). 0.5: an iteration on the kept factors costs a residual and a
  /// back-substitution, a refresh the whole tangent and a GMRES solve, about 8x as much on the lung
  /// (docs/MESHLESS.md §2, "Why 2× and not 5×": 0.2 before, 1.32× slower over lung_small's run).
  double refactor_contraction = 0.5;
  /// When the kept factors stop contracting (above), the new tangent is first solved by GMRES preconditioned
  /// with those factors (a few back-substitutions), and factorised only when GMRES needs more than this many
  /// iterations to reach iterative_tolerance. Direct solvers only; 0 always factorises. docs/MESHLESS.md §2.
  int earlier_factors_max_iterations = 30;
  /// That GMRES solve stops at the relative residual max(gmres_forcing * ||R|| / ||F||, half of what Newton still
  /// needs), within [iterative_tolerance, gmres_forcing] (Eisenstat & Walker 1996, as the FEM reference's GMRES):
  /// Newton's next residual is then about as small as with an exact solve. 0: solve to iterative_tolerance.
  /// docs/MESHLESS.md §2, "How far GMRES solves".
  double gmres_forcing = 0.1;
  /// Anderson mixing of the updates on kept factors (meshless/solvers/anderson_acceleration.hpp): how many earlier
  /// updates each mix uses. 0: plain iterations on the kept factors. A failed mixed attempt is retried plain
  /// before the step is halved. docs/MESHLESS.md §2, "Anderson mixing and the predictor".
  int anderson_depth = 5;
  /// Start each step's Newton iteration from U_n + (dt_{n+1} / dt_n)(U_n - U_{n-1}) instead of U_n, while the
  /// load keeps its rate (the ramp, or the hold). Changes the path only; the converged answer is the same.
  bool extrapolate_start = true;
  LinearSolverKind linear_solver = LinearSolverKind::automatic;
  /// > 0: the direct solver (MUMPS) factorises with block low-rank compression at this dropping tolerance
  /// (meshless/solvers/mumps_lu.hpp): an approximate LU that Newton's own test corrects, as it does the kept
  /// factors of an older tangent. 0: the exact LU. docs/MESHLESS.md §2, "Low-rank factors".
  double direct_low_rank_tolerance = 0.0;
  /// The direct solver (MUMPS) factorises the symmetric part (K + K^T) / 2 by LDL^T: half the work of the LU, and
  /// factors that are exact only where K is symmetric (VCI and k != 0 make it slightly not). Newton's test corrects
  /// the difference, as for kept factors of an older tangent. docs/MESHLESS.md §2, "Factors of the symmetric part".
  bool direct_symmetric_part = true;
  /// The direct solver's analysis orders the graph of the nodes (MUMPS ICNTL(15) = -3, MumpsLu's block_size) rather
  /// than that of the unknowns: 19 % fewer operations on lung_small's tangent (docs/PERFORMANCE.md, "MUMPS orders
  /// the node graph"). false: the unknowns' graph, as before (kept for that comparison).
  bool direct_node_ordering = true;
  /// automatic: factorise when the estimated peak memory of the LU (meshless/solvers/direct_solver_estimate.hpp, AMD on
  /// the node pairs) is below this fraction of the memory available when the matrix has been allocated
  /// (available_memory(): the cgroup limit, else MemAvailable); the rest is a margin for the estimate's error.
  double direct_solver_memory_fraction = 0.8;
  /// PETSc options of the petsc_krylov solver (its own options database; docs/MESHLESS.md §2 has the measurements
  /// behind the choice): LGMRES(100), left-preconditioned by SSOR applied through Eisenstat's trick, so that an
  /// iteration costs one pass over the tangent (two triangular sweeps) instead of a product and a sweep. SSOR-GMRES
  /// alone matched ML with Krylov level smoothers: the wide EFG rows make the ML hierarchy too coarse to help
  /// (docs/MESHLESS.md §2, "The iterative solver"). The earlier default is kMlWithGcrSmoothersOptions.
  std::string krylov_options = "-ksp_type lgmres -ksp_gmres_restart 100 -pc_type eisenstat";
  /// > 0: the petsc_krylov solver builds its preconditioner (for example an ML hierarchy and its levels' SOR sweeps)
  /// from a copy of the tangent without its small entries: an entry a_ij is dropped when |a_ij| < this *
  /// sqrt(|a_ii a_jj|) and i, j belong to different nodes; the Krylov method still applies the whole tangent. At 0.01
  /// the copy keeps about a quarter of the entries (docs/MESHLESS.md §2, "A sparser matrix for the preconditioner").
  /// 0 (the default) preconditions with the tangent itself, which Eisenstat's trick needs: PetscKrylovSolver refuses
  /// a drop tolerance with -pc_type eisenstat.
  double preconditioner_drop_tolerance = 0.0;
  /// Relative residual of each iterative solve. Newton's own test decides convergence, so a looser solve only
  /// costs Newton iterations: 1e-9 lets one Newton iteration finish an elastic step at newton_tolerance 1e-8.
  double iterative_tolerance = 1e-9;
  int iterative_max_iterations = 20000;
  /// Under mpirun with more than one process: distribute the petsc_krylov solve over all of them (every process
  /// must then build the same model and step it in lock-step; meshless/solvers/petsc_krylov_solver.hpp), and let the
  /// automatic choice take it rather than repeat one factorisation on every process. false: each process solves
  /// alone, as with one process. No effect with one process.
  bool distributed_krylov_solve = true;
};

struct EfgProblem {
  std::string name;
  /// Vertices = EFG nodes, tets = background integration cells, boundary faces (outward) for the surface
  /// integrals of eqs. 23-24. face_tags select where penalty and traction act unless the masks below are set.
  core::TetMesh mesh;
  core::KelvinParameters material;
  SupportRadiiParams support;  ///< rho_i = d_max * distance to the k-th neighbour
  int quadrature_order = 2;    ///< background-cell rule (tet_rule) and face rule (triangle_rule)
  double node_spacing = 0.0;   ///< [m], scales alpha
  double penalty_factor = 1e3; ///< alpha = penalty_factor * K1 / node_spacing  (eq. 23)

  /// Boundary roles per boundary face (#F). Empty -> derived from mesh.face_tags (fixed / load).
  std::vector<char> penalised_faces;
  std::vector<char> loaded_faces;
  /// An elastic support (core::FixedRegionSpec, support "elastic"): when set, the penalised faces carry
  /// alpha(x) = support_stiffness(x) [Pa/m] instead of alpha(). Eq. 23 with this alpha is the Robin term
  /// t = -k_s u itself, so the support is imposed exactly, as the FEM reference imposes it.
  std::function<double(const Eigen::Vector3d&)> support_stiffness;
  /// u-bar on the penalised faces (eq. 19, 23); empty -> zero. Held constant in time.
  VectorField prescribed_displacement;
  /// Traction t-bar [Pa] on the loaded faces at full load (eq. 24), scaled by load_scale(t).
  VectorField traction;
  std::function<double(double)> load_scale = [](double) { return 1.0; };
  /// Times t_1 < t_2 < ... of the steps (t_0 = 0). dt = t_n - t_{n-1}; a first step at t = 0 has dt = 0,
  /// an instantaneous (elastic, K1) response.
  std::vector<double> step_times;
  /// When Newton fails on a step, the step is halved and retried down to this size [s] (core/step_cutback.hpp);
  /// 0 disables the cut-back.
  double min_step = 0.0;
  /// Steps at which output_results() writes (the last step is always written). Empty -> every step.
  int output_every = 1;

  /// The incision (paper §4) when the body is cut: the shape functions are made discontinuous across it by
  /// `cut_treatment` (meshless/cut/cut_weights.hpp), the background cells and boundary faces it crosses are split, and
  /// its two lips become boundary (traction-free unless lip_traction is set).
  std::optional<core::RuledSurface> cut;
  CutTreatment cut_treatment = CutTreatment::enrichment;
  /// l of the enrichment's front transition [m] (meshless/cut/cut_weights.hpp); 0 = the paper's phi as it stands.
  double front_transition = 0.0;
  /// Variationally consistent integration (Chen, Hillman & Rueter 2013, linear VCI): add a constant per node
  /// to the test-function gradients so the discrete divergence theorem int grad phi_i = oint phi_i n holds
  /// for the background quadrature. Makes the linear patch test pass to round-off; off = the paper's plain eq. 22.
  /// Part of the discrete problem (it changes the answer), so it lives here and not among the solver's options.
  bool variationally_consistent = true;
  /// Traction on the lips at full load (scaled by load_scale(t)); empty = traction-free, as an incision is.
  /// Verification problems load them with sigma n.
  LipTraction lip_traction;

  double alpha() const { return penalty_factor * material.K1 / node_spacing; }
};

/// The load case of a config: meshless_mesh of the geometry, the fixed faces penalised (a clamp: alpha() and zero
/// u-bar; an elastic support: alpha = k_s(x) of the case), uniform traction
/// force(t) / A_patch on the load faces (core::load_program), the geometry's cut (if any) with the case's
/// treatment (/meshless/enrichment) and front transition (/meshless/front_transition), and the quadrature's
/// consistency correction (/meshless/variationally_consistent; both set by /meshless/preset).
EfgProblem problem_from_case(const core::Case& c, const core::Geometry& g);

}  // namespace meshless
