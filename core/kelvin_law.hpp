#pragma once
// The nonlinear Kelvin viscoelastic law (paper §2, eqs. 9–13), shared by the meshless model and the FEM
// reference so that both solve exactly the same constitutive problem.
//
// Reading (see docs/MATERIAL.md):
//  * Kelvin = standard linear solid (Fig. 2): spring K1 in series with (spring K2 || damper eta).
//    Relaxation modulus E(t) = E_inf + (K1 - E_inf) exp(-t/tau),  E_inf = K1 K2/(K1+K2),  tau = eta/(K1+K2).
//  * Adjustment function, frame-indifferent 3-D form: N(eps) = eps + k eps.eps (matrix product).
//  * 3-D stress (eq. 10): sigma(t) = int_0^t g(t-s) C0 : dN/ds ds,  g = E/K1,  C0 = isotropic(K1, nu).
//  * Exact one-step recursion for the exponential kernel (eqs. 11–13): one internal Voigt stress h per
//    quadrature point, so each step costs O(1) regardless of the history length.
#include "core/voigt.hpp"

namespace core {

/// Material constants in SI units (Pa, Pa·s, dimensionless).
struct KelvinParameters {
  double K1 = 0.0;   ///< instantaneous spring stiffness [Pa]
  double K2 = 0.0;   ///< spring parallel to the damper [Pa]
  double eta = 0.0;  ///< damper viscosity [Pa s]
  double nu = 0.0;   ///< Poisson's ratio of the isotropic elastic tensor
  double k = 0.0;    ///< adjustment-function coefficient in N(eps) = eps + k eps^2 [-]
  /// The smallest slope the adjustment function may reach, delta in [0, 1) (docs/MATERIAL.md §1.7). 0 is the
  /// paper's law: its slope 1 + 2k lambda reaches 0 at the limit strain -1/(2k) and no equilibrium exists past
  /// it. With delta > 0, N continues past the principal strain where its slope falls to delta as a straight line
  /// of slope delta, so every strain is admissible; inside that strain the law is the paper's, bit for bit.
  double slope_floor = 0.0;

  double relaxation_time() const { return eta / (K1 + K2); }             ///< tau
  double equilibrium_modulus() const { return K1 * K2 / (K1 + K2); }     ///< E_inf
  double relaxation_modulus(double t) const;                             ///< E(t)
};

/// History carried at one quadrature point between time steps.
struct KelvinState {
  Vector6 strain = Vector6::Zero();          ///< total engineering strain at t_n
  Vector6 adjusted_strain = Vector6::Zero(); ///< N(eps) at t_n, engineering Voigt form (output only:
                                             ///< update() recomputes N_n from `strain`)
  Vector6 viscous_stress = Vector6::Zero();  ///< h_n, the decaying part of the hereditary integral
  Vector6 stress = Vector6::Zero();          ///< sigma_n
};

/// Result of one constitutive update.
struct KelvinResponse {
  Vector6 stress;   ///< sigma_{n+1}
  Matrix6 tangent;  ///< consistent tangent d sigma_{n+1} / d eps_{n+1} (E_k of eq. 13, incl. dN/deps)
};

class KelvinLaw {
 public:
  explicit KelvinLaw(const KelvinParameters& parameters);

  const KelvinParameters& parameters() const { return parameters_; }

  /// Isotropic elastic matrix for Young's modulus E and the law's nu (maps engineering strain to stress).
  Matrix6 elastic_matrix(double youngs_modulus) const;

  /// N(eps) in engineering Voigt form, and its Jacobian dN/deps (6x6).
  Vector6 adjusted_strain(const Vector6& strain) const;
  Matrix6 adjusted_strain_jacobian(const Vector6& strain) const;

  /// Principal strains (eigenvalues of the strain tensor), ascending.
  static Eigen::Vector3d principal_strains(const Vector6& strain);

  /// The admissible range of N (docs/MATERIAL.md §1.5). In the principal frame of eps, dN/deps scales a
  /// strain increment's (i, j) component by 1 + k (lambda_i + lambda_j), so its smallest eigenvalue is
  /// min_i (1 + 2 k lambda_i), which this returns (1 for k = 0). The consistent tangent is that factor times
  /// C0 in its weakest direction: at 0 it is singular, below 0 N is no longer monotone and no equilibrium
  /// exists past the peak of N. A strain is admissible while the margin is > 0.
  double admissibility_margin(const Vector6& strain) const;
  /// The principal strain at which the margin vanishes, -1/(2k): compressive for k > 0, tensile for k < 0,
  /// infinite for k = 0.
  double limit_strain() const;
  /// Whether a strain with this margin has an equilibrium under this law: a margin > 0, or any margin when the
  /// slope floor continues N past its limit (then the margin still reports the paper's 1 + 2k lambda, so that a
  /// margin below the floor shows where the continuation acted).
  bool admits(double margin) const { return margin > 0.0 || parameters_.slope_floor > 0.0; }
  /// The principal strain past which the slope floor continues N linearly, (delta - 1)/(2k); infinite when
  /// k = 0 or the floor is 0 (the paper's law everywhere).
  double floor_strain() const;

  /// Effective step modulus factor: g_inf + (1-g_inf) (tau/dt)(1 - exp(-dt/tau)).  dt = 0 -> 1.
  double step_modulus_factor(double dt) const;

  /// Advance from `old_state` (at t_n) to strain `strain_new` at t_{n+1} = t_n + dt.
  /// Writes the new history into `new_state` when it is non-null. Pure function otherwise.
  KelvinResponse update(const KelvinState& old_state, const Vector6& strain_new, double dt,
                        KelvinState* new_state = nullptr) const;

  /// update()'s stress and history without the consistent tangent, for the residual-only evaluations of a
  /// modified Newton iteration: the tangent (dN/deps and a 6x6 product) is most of update()'s work and would
  /// be discarded there. Bit-identical to update().stress.
  Vector6 updated_stress(const KelvinState& old_state, const Vector6& strain_new, double dt,
                         KelvinState* new_state = nullptr) const;

 private:
  /// True when a principal strain lies past floor_strain(), where N is evaluated in the principal frame.
  bool past_floor(const Vector6& strain) const;
  /// The 1-D adjustment function with the slope floor, its slope, and the divided difference
  /// (n(a) - n(b)) / (a - b) (the slope at a = b): the factors of the principal-frame form of N and dN/deps.
  double floored_n(double lambda) const;
  double floored_slope(double lambda) const;
  double floored_divided_difference(double a, double b) const;

  KelvinParameters parameters_;
  Matrix6 C0_;  // elastic_matrix(K1)
};

}  // namespace core
