#pragma once
#include <functional>
// Verification problems of the LRPIM model with known answers (docs/LRPIM.md §4), the counterparts of the EFG's
// (meshless/verification/verification_problems.hpp): RPIM invariants, the linear patch test, the Timoshenko
// cantilever's convergence rates, and the closed-form creep of a bar at k = 0 and k != 0. Node clouds are the
// vertices of meshless::make_box_mesh; its tets are not used.
#include <nlohmann/json.hpp>
#include <vector>

#include "meshless/lrpim/lrpim_problem.hpp"
#include "meshless/lrpim/rpim_shape_functions.hpp"
#include "meshless/verification/invariant_report.hpp"

namespace meshless::lrpim {

/// The consistency errors every linearly complete family has (meshless::InvariantReport) and what only an
/// interpolant has.
struct RpimInvariantReport : InvariantReport {
  double max_kronecker_error = 0.0;        ///< max_ij |phi_i(X_j) - delta_ij| over nodes X_j
  double min_rcond = 1.0;                  ///< smallest rcond of G met
  double min_spread = 1.0;                 ///< smallest RpimEvaluation::spread met [d_c^2]
};
/// On the jittered 11^3 cloud of the EFG's invariants (spacing 10 mm, jitter 0.2), at `points` random points and
/// at every node.
RpimInvariantReport rpim_invariants(const RpimParameters& parameters = {}, int points = 2000, unsigned seed = 7);

struct LrpimPatchReport {
  int num_nodes = 0, cells = 0;
  double max_relative_error = 0.0;     ///< max |u_h - u| / max |u| over random interior points
  double nodal_relative_error = 0.0;   ///< same over the nodes (u_h(X_i) = U_i)
  double strain_relative_error = 0.0;  ///< max |eps_h - eps| / |eps| at the random points
  int newton_iterations = 0;
  double divergence_defect = 0.0;      ///< LrpimStatistics::divergence_defect (before any correction)
};
/// Cube of edge 50 mm, `cells` per axis, interior nodes jittered by 0.2 cells; u = a + G X prescribed at the
/// nodes of the -x, -y, -z faces, the traction sigma n of the exact constant stress on the +x, +y, +z faces
/// (nu = 0.3, instantaneous elastic step). `alpha_q`, `rule`: the local domain and its quadrature.
/// `divergence_correction`: LrpimProblem::divergence_correction. `cloud_surface`: the body is the box mesh's own
/// boundary triangles (2 per boundary cell face, their vertices the surface nodes), as a load case's body is,
/// instead of the box's 12 triangles.
LrpimPatchReport run_lrpim_patch_test(int cells = 5, double alpha_q = 1.5, int polar = 8, int azimuthal = 16,
                                      bool divergence_correction = true, bool cloud_surface = false);

struct LrpimCantileverReport {
  int cells_through_height = 0, num_nodes = 0;
  double node_spacing = 0.0;  ///< [m]
  double l2_error = 0.0;      ///< ||u_h - u||_L2 / ||u||_L2 (tensor Gauss grid over the beam)
  double energy_error = 0.0;  ///< ||eps_h - eps||_C / ||eps||_C
  double tip_deflection = 0.0, exact_tip_deflection = 0.0;  ///< u_y at (L, 0, 0) [m]
  double seconds = 0.0;       ///< set-up + assembly + solve
};
/// The EFG's cantilever (L 100 mm, D = T = 20 mm, K1 = 6000 Pa, nu = 0, shear P = 1 mN at x = L, parabolic):
/// the exact Timoshenko & Goodier displacement prescribed at the x = 0 nodes, the exact parabolic traction at
/// x = L, the other faces free; 5 nd by nd by nd cells of the box mesh's node grid (regular, no jitter).
LrpimProblem lrpim_cantilever_problem(int cells_through_height, const RpimParameters& rpim = {}, double alpha_q = 1.5);

/// The cantilever above, solved, with its errors against the closed form. `adjust` (optional) may change the problem
/// before the set-up (a rule, the test function; for studies of the rates, docs/LRPIM.md §4).
LrpimCantileverReport run_lrpim_cantilever(int cells_through_height, const RpimParameters& rpim = {},
                                           double alpha_q = 1.5,
                                           const std::function<void(LrpimProblem*)>& adjust = {});

struct LrpimCreepReport {
  double k = 0.0;
  std::vector<double> times, strain, exact;  ///< [s], (u_x(L) - u_x(0)) / L, closed form
  double max_relative_error = 0.0;
  int num_nodes = 0;
};
/// The EFG's creep bar (40 x 10 x 10 mm, 8 x 2 x 2 cells, nu = 0, K1 = 6000, K2 = 12000, eta = 18000): u = 0 at the
/// x = 0 nodes, step traction sigma0 = 100 Pa at x = L from t = 0 (first step dt = 0), then `steps` steps to 4 s.
/// The stress is uniaxial and uniform, so the law is linear in N(eps) = eps + k eps^2 (docs/MATERIAL.md §1.2):
/// N(t) = sigma0/K1 + sigma0/K2 (1 - exp(-K2 t/eta)) and eps = (sqrt(1 + 4 k N) - 1) / (2 k) (eps = N at k = 0).
LrpimCreepReport run_lrpim_creep_bar(double k = 0.0, int steps = 40);

/// The verification set of `tissue verify lrpim`, every figure as JSON: RPIM invariants, the patch test (the box's
/// 12 triangles with and without the divergence correction, and the cloud's own boundary triangles), the cantilever's
/// errors and fitted rates, and the creep bar at k = 0 and k = 2. Each item carries its figures, the bound the tests
/// assert (tests/test_lrpim.cpp) and `passed`; the top level has `passed` (all items) and `seconds`.
/// quick: a smaller set for a smoke run (invariants at 500 points, the patch tests at 4 cells, the cantilever at 2
/// and 3 cells, the creep bars over 10 steps), whose bounds are looser where the smaller set is less accurate.
/// Thread safety: uses OpenMP inside; call from one thread. No MPI needed (SparseLU).
nlohmann::json run_lrpim_verification(bool quick);

}  // namespace meshless::lrpim
