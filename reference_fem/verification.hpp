#pragma once
// Verification problems of the FEM reference against closed forms (deal.II-free header):
//  * uniaxial relaxation and creep of the standard linear solid (paper Fig. 2, eqs. 9–13),
//  * the 3-D cantilever against the Timoshenko beam solution (elastic limit), for L2 convergence rates.
#include <vector>

#include "core/kelvin_law.hpp"
#include "reference_fem/problem.hpp"

namespace reference_fem {

/// One uniaxial history: a bar [0,L]x[0,W]x[0,W] with roller symmetry planes x=0, y=0, z=0 (lateral
/// faces free, so the 1-D formulas hold for any nu), loaded on x=L at t = 0 in an instantaneous step.
struct UniaxialOptions {
  core::KelvinParameters material;
  int degree = 2;
  double end_time = 1.0;  ///< [s]
  int steps = 100;        ///< after the instantaneous step at t = 0
};

struct UniaxialSample {
  double time = 0.0;      ///< [s]
  double computed = 0.0;  ///< sigma_xx (relaxation) or eps_xx (creep) of the FEM
  double exact = 0.0;     ///< closed form
};

struct UniaxialResult {
  std::vector<UniaxialSample> history;
  double max_relative_error = 0.0;
  int max_newton_iterations = 0;
  /// strain_in_ball over a ball of radius 0.4 in the middle of the bar at the last step (a uniform field).
  BallStrain final_ball_strain;
  /// Elastic support only: max over the steps of |u_x(0) - sigma0/k_s| / (sigma0/k_s), u_x(0) the displacement of
  /// the supported end (the Robin term t = -k_s u against the closed form).
  double max_support_relative_error = 0.0;
};

/// What the closed forms are held to (tests/test_fem_verification.cpp and `tissue verify fem`), near what is reached:
/// the recursion is exact for a held step strain (round-off, 3e-15); under a held stress the strain varies within
/// each step, which the recursion takes as linear (6.4e-5 at dt = tau/10); the elastic support's displacement is a
/// linear field that P2 holds exactly.
constexpr double kRelaxationTolerance = 1e-12;
constexpr double kCreepTolerance = 1e-4;
constexpr double kSupportDisplacementTolerance = 1e-9;

/// Step strain eps0 held: sigma(t) = eps0 K1/(K1+K2) [K2 + K1 exp(-t/tau)], tau = eta/(K1+K2).
UniaxialResult run_uniaxial_relaxation(const UniaxialOptions& options, double eps0);
/// Step stress sigma0 held: eps(t) = sigma0/K1 + sigma0/K2 (1 - exp(-K2 t/eta)).
UniaxialResult run_uniaxial_creep(const UniaxialOptions& options, double sigma0);
/// The creep bar held at x = 0 by an elastic support of stiffness k_s [Pa/m] instead of the roller plane (the planes
/// y = 0 and z = 0 stay rollers; use nu = 0, so that the support's tangential springs carry no load): a bar on a
/// spring in series. Exact: u_x(x, t) = sigma0 / k_s + x eps(t), with eps(t) the creep curve above.
UniaxialResult run_uniaxial_creep_on_elastic_support(const UniaxialOptions& options, double sigma0,
                                                     double support_stiffness);

/// Cantilever [0,L]x[-D/2,D/2]x[0,B] clamped at x = 0 to the exact displacement, parabolic end shear P
/// at x = L; nu = 0 so the plane-stress Timoshenko solution is an exact 3-D solution. Elastic limit:
/// k = 0 and one instantaneous (dt = 0) step, so the modulus is K1.
struct CantileverOptions {
  double length = 0.1, depth = 0.02, width = 0.02;  ///< [m]
  double force = 1.0e-3;                            ///< end shear P [N]
  double youngs_modulus = 6000.0;                   ///< K1 [Pa]
  int degree = 2;
};

struct CantileverLevel {
  int subdivisions = 0;  ///< elements through the depth (5x along the length)
  double h = 0.0;        ///< hexahedron edge before the split into tetrahedra [m]
  std::size_t n_dofs = 0;
  double l2_error = 0.0;           ///< ||u_h - u||_L2 / ||u||_L2
  double tip_deflection = 0.0;     ///< FEM u_y at (L, 0, B/2) [m]
  double exact_tip_deflection = 0.0;
  double seconds = 0.0;
  int newton_iterations = 0;
};

CantileverLevel run_cantilever(const CantileverOptions& options, int subdivisions);

/// The L2 errors' order over the levels: core::convergence_rate of (h, l2_error).
double convergence_rate(const std::vector<CantileverLevel>& levels);

}  // namespace reference_fem
