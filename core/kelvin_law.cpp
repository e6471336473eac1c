// Nonlinear Kelvin viscoelastic law of Zhang et al. 2020, §2, eqs. 9–13 (see core/kelvin_law.hpp and
// docs/MATERIAL.md for the full reading).
//
// Summary of the discretisation implemented here:
//  * Relaxation modulus of the standard linear solid (Fig. 2; spring K1 in series with K2 || eta):
//        E(t) = E_inf + (K1 - E_inf) exp(-t/tau),  E_inf = K1 K2/(K1+K2),  tau = eta/(K1+K2).
//    Normalised kernel g(t) = E(t)/K1 = g_inf + (1 - g_inf) exp(-t/tau).
//  * Eq. 10 in 3-D:  sigma(t) = int_0^t g(t-s) C0 : dN/ds ds,  N(eps) = eps + k eps.eps,  C0 = C(K1, nu).
//  * Because the kernel is one exponential plus a constant, sigma splits into an elastic part and one
//    decaying internal stress h:
//        sigma = g_inf C0 N(eps) + h,   h(t) = (1 - g_inf) int_0^t exp(-(t-s)/tau) C0 dN/ds ds.
//    Splitting the integral at t_n (eq. 12) gives the exact recursion, assuming dN/ds is constant on
//    (t_n, t_{n+1}] (N linear in time within the step):
//        h_{n+1} = exp(-dt/tau) h_n + (1 - g_inf) phi(dt) C0 (N_{n+1} - N_n),
//        phi(dt) = (tau/dt) (1 - exp(-dt/tau)),  phi(0) = 1.
//    Hence the incremental form of eq. 13:  Delta sigma = E_k Delta N + sigma_0 with
//        E_k = [g_inf + (1 - g_inf) phi] C0   (times dN/deps to act on Delta eps),
//        sigma_0 = (exp(-dt/tau) - 1) h_n.
#include "core/kelvin_law.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

namespace core {

namespace {

// Builds "KelvinLaw: <what> (got <value>)" so that a bad input names itself in the exception.
std::string describe(const std::string& what, double value) {
  std::ostringstream out;
  out.precision(17);
  out << "KelvinLaw: " << what << " (got " << value << ")";
  return out.str();
}

void require_positive(const char* name, double value) {
  // `!(value > 0)` also rejects NaN.
  if (!(value > 0.0) || !std::isfinite(value)) {
    throw std::invalid_argument(describe(std::string(name) + " must be finite and > 0", value));
  }
}

bool all_finite(const Vector6& v) { return v.allFinite(); }

}  // namespace

double KelvinParameters::relaxation_modulus(double t) const {
  const double e_inf = equilibrium_modulus();
  return e_inf + (K1 - e_inf) * std::exp(-t / relaxation_time());
}

KelvinLaw::KelvinLaw(const KelvinParameters& parameters) : parameters_(parameters) {
  require_positive("K1", parameters_.K1);
  require_positive("K2", parameters_.K2);
  require_positive("eta", parameters_.eta);
  // nu = 0.5 makes lambda infinite (incompressible); nu <= -1 makes the shear modulus non-positive.
  if (!(parameters_.nu > -1.0 && parameters_.nu < 0.5)) {
    throw std::invalid_argument(describe("nu must satisfy -1 < nu < 0.5", parameters_.nu));
  }
  if (!std::isfinite(parameters_.k)) {
    throw std::invalid_argument(describe("k must be finite", parameters_.k));
  }
  if (!(parameters_.slope_floor >= 0.0 && parameters_.slope_floor < 1.0)) {
    throw std::invalid_argument(describe("slope_floor must satisfy 0 <= slope_floor < 1", parameters_.slope_floor));
  }
  C0_ = elastic_matrix(parameters_.K1);
}

Matrix6 KelvinLaw::elastic_matrix(double youngs_modulus) const {
  const double nu = parameters_.nu;
  const double lambda = youngs_modulus * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
  const double mu = youngs_modulus / (2.0 * (1.0 + nu));
  Matrix6 c = Matrix6::Zero();
  c.topLeftCorner<3, 3>().setConstant(lambda);
  c.topLeftCorner<3, 3>().diagonal().array() += 2.0 * mu;
  // Strain vectors carry engineering shear gamma = 2 eps, so sigma_xy = 2 mu eps_xy = mu gamma_xy.
  c.bottomRightCorner<3, 3>().diagonal().setConstant(mu);
  return c;
}

Vector6 KelvinLaw::adjusted_strain(const Vector6& strain) const {
  if (past_floor(strain)) {
    // The slope floor (§1.7): N is the isotropic tensor function with the 1-D function n of each principal
    // strain, N = sum_i n(lambda_i) v_i v_i^T. Inside the floor n(lambda) = lambda + k lambda^2 and this is
    // exactly eps + k eps.eps, so the switch is continuous; it is taken only past the floor, and the paper's
    // polynomial below stays the law everywhere else, bit for bit.
    const Eigen::SelfAdjointEigenSolver<Matrix3> eigen(voigt_to_strain(strain));
    const Eigen::Vector3d lambda = eigen.eigenvalues();
    const Eigen::Vector3d n(floored_n(lambda[0]), floored_n(lambda[1]), floored_n(lambda[2]));
    return strain_to_voigt(eigen.eigenvectors() * n.asDiagonal() * eigen.eigenvectors().transpose());
  }
  // Tensor form N = eps + k eps.eps (the 3-D reading of the 1-D N = eps + k eps^2 in eq. 10). It is an
  // isotropic tensor function, so N(R eps R^T) = R N(eps) R^T: the law is frame-indifferent. A
  // component-wise square of the Voigt vector would not be (and would mix engineering factors of 2).
  const Matrix3 e = voigt_to_strain(strain);
  const Matrix3 n = e + parameters_.k * (e * e);
  return strain_to_voigt(n);
}

Matrix6 KelvinLaw::adjusted_strain_jacobian(const Vector6& strain) const {
  // dN = de + k (de.e + e.de) is linear in de, so column j of dN/deps is the engineering Voigt image of
  // that expression for de = voigt_to_strain(unit vector j). Going through voigt_to_strain handles the
  // halving of engineering shear on input and strain_to_voigt the doubling on output, which is the
  // easy thing to get wrong when writing this 6x6 matrix by hand.
  if (past_floor(strain)) {
    // The derivative of an isotropic tensor function (Daleckii-Krein): in the principal frame the (i, j)
    // component of d eps is scaled by n'(lambda_i) when i = j and by the divided difference
    // (n(lambda_i) - n(lambda_j)) / (lambda_i - lambda_j) when i != j. With the paper's polynomial these are
    // 1 + 2k lambda_i and 1 + k (lambda_i + lambda_j), the factors of §1.5, so both forms agree inside the floor.
    const Eigen::SelfAdjointEigenSolver<Matrix3> eigen(voigt_to_strain(strain));
    const Eigen::Vector3d lambda = eigen.eigenvalues();
    const Matrix3& v = eigen.eigenvectors();
    Matrix3 factor;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        factor(a, b) = a == b ? floored_slope(lambda[a]) : floored_divided_difference(lambda[a], lambda[b]);
    Matrix6 jacobian;
    for (int j = 0; j < 6; ++j) {
      const Matrix3 de = v.transpose() * voigt_to_strain(Vector6::Unit(j)) * v;
      jacobian.col(j) = strain_to_voigt(v * factor.cwiseProduct(de) * v.transpose());
    }
    return jacobian;
  }
  const Matrix3 e = voigt_to_strain(strain);
  const double k = parameters_.k;
  Matrix6 jacobian;
  for (int j = 0; j < 6; ++j) {
    const Matrix3 de = voigt_to_strain(Vector6::Unit(j));
    jacobian.col(j) = strain_to_voigt(de + k * (de * e + e * de));
  }
  return jacobian;
}

Eigen::Vector3d KelvinLaw::principal_strains(const Vector6& strain) {
  // Closed-form 3x3 eigenvalues: this runs at every integration point in every Newton iteration, and the
  // margin only needs a few correct digits.
  Eigen::SelfAdjointEigenSolver<Matrix3> eigen;
  eigen.computeDirect(voigt_to_strain(strain), Eigen::EigenvaluesOnly);
  return eigen.eigenvalues();
}

double KelvinLaw::admissibility_margin(const Vector6& strain) const {
  const double k = parameters_.k;
  if (k == 0.0) return 1.0;
  const Eigen::Vector3d lambda = principal_strains(strain);
  // 1 + 2 k lambda is smallest at the smallest principal strain for k > 0 and at the largest for k < 0.
  return 1.0 + 2.0 * k * (k > 0.0 ? lambda.minCoeff() : lambda.maxCoeff());
}

double KelvinLaw::limit_strain() const {
  const double k = parameters_.k;
  return k == 0.0 ? std::numeric_limits<double>::infinity() : -1.0 / (2.0 * k);
}

double KelvinLaw::floor_strain() const {
  const double k = parameters_.k, delta = parameters_.slope_floor;
  return k == 0.0 || delta == 0.0 ? std::numeric_limits<double>::infinity() : (delta - 1.0) / (2.0 * k);
}

bool KelvinLaw::past_floor(const Vector6& strain) const {
  // No floor (or k = 0, where the margin is 1): the paper's law, without computing an eigenvalue.
  if (parameters_.k == 0.0 || parameters_.slope_floor == 0.0) return false;
  return admissibility_margin(strain) < parameters_.slope_floor;
}

// n(lambda) = lambda + k lambda^2 while its slope 1 + 2k lambda is >= delta; past lambda_c = (delta - 1)/(2k)
// the tangent line at lambda_c, n(lambda_c) + delta (lambda - lambda_c). n is continuous with its slope, so
// Newton sees no kink in the stress, only in its derivative.
double KelvinLaw::floored_n(double lambda) const {
  const double k = parameters_.k, delta = parameters_.slope_floor;
  if (1.0 + 2.0 * k * lambda >= delta) return lambda + k * lambda * lambda;
  const double c = floor_strain();
  return c + k * c * c + delta * (lambda - c);
}

double KelvinLaw::floored_slope(double lambda) const {
  return std::max(parameters_.slope_floor, 1.0 + 2.0 * parameters_.k * lambda);
}

double KelvinLaw::floored_divided_difference(double a, double b) const {
  const double k = parameters_.k, delta = parameters_.slope_floor;
  const bool a_inside = 1.0 + 2.0 * k * a >= delta, b_inside = 1.0 + 2.0 * k * b >= delta;
  if (a_inside && b_inside) return 1.0 + k * (a + b);  // exact, no cancellation
  if (!a_inside && !b_inside) return delta;
  // One on each side of lambda_c: the quotient is well conditioned unless a and b nearly coincide, where the
  // slope (continuous, equal to delta at lambda_c) is the limit.
  if (std::abs(a - b) <= 1e-12 * std::max({1.0, std::abs(a), std::abs(b)})) return floored_slope(0.5 * (a + b));
  return (floored_n(a) - floored_n(b)) / (a - b);
}

double KelvinLaw::step_modulus_factor(double dt) const {
  const double tau = parameters_.relaxation_time();
  const double g_inf = parameters_.equilibrium_modulus() / parameters_.K1;
  const double a = dt / tau;
  // phi = (1 - exp(-a))/a; -expm1 keeps full precision as a -> 0, and a = 0 is the instantaneous limit.
  const double phi = (a > 0.0) ? -std::expm1(-a) / a : 1.0;
  return g_inf + (1.0 - g_inf) * phi;
}

Vector6 KelvinLaw::updated_stress(const KelvinState& old_state, const Vector6& strain_new, double dt,
                                  KelvinState* new_state) const {
  // Reject inputs that would otherwise propagate NaN silently into a global solve.
  if (!(dt >= 0.0) || !std::isfinite(dt)) {
    throw std::invalid_argument(describe("time step dt must be finite and >= 0", dt));
  }
  if (!all_finite(strain_new)) {
    throw std::invalid_argument("KelvinLaw::update: strain_new has a non-finite component");
  }
  if (!all_finite(old_state.strain) || !all_finite(old_state.viscous_stress)) {
    throw std::invalid_argument("KelvinLaw::update: old_state holds a non-finite strain or viscous stress");
  }

  const double tau = parameters_.relaxation_time();
  const double g_inf = parameters_.equilibrium_modulus() / parameters_.K1;
  const double a = dt / tau;
  const double decay = std::exp(-a);                         // exp(-dt/tau)
  const double phi = (a > 0.0) ? -std::expm1(-a) / a : 1.0;  // (tau/dt)(1 - exp(-dt/tau))

  // N_n is recomputed from the stored strain rather than read from old_state.adjusted_strain, so a state
  // built by hand (e.g. a prestrain with zero history) is always self-consistent.
  const Vector6 n_old = adjusted_strain(old_state.strain);
  const Vector6 n_new = adjusted_strain(strain_new);

  // Eq. 12: history part decays exactly, the new increment is integrated against the kernel on the step.
  const Vector6 h_new = decay * old_state.viscous_stress + (1.0 - g_inf) * phi * (C0_ * (n_new - n_old));
  const Vector6 stress = g_inf * (C0_ * n_new) + h_new;

  if (new_state != nullptr) {
    new_state->strain = strain_new;
    new_state->adjusted_strain = n_new;
    new_state->viscous_stress = h_new;
    new_state->stress = stress;
  }
  return stress;
}

KelvinResponse KelvinLaw::update(const KelvinState& old_state, const Vector6& strain_new, double dt,
                                 KelvinState* new_state) const {
  KelvinResponse response;
  response.stress = updated_stress(old_state, strain_new, dt, new_state);
  // d sigma_{n+1}/d eps_{n+1} = [g_inf + (1 - g_inf) phi] C0 dN/deps: E_k of eq. 13 including the
  // adjustment-function Jacobian. Not symmetric when k != 0 (C0 J != J^T C0 in general).
  response.tangent = step_modulus_factor(dt) * (C0_ * adjusted_strain_jacobian(strain_new));
  return response;
}

}  // namespace core
