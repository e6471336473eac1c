#pragma once
// Levenberg-Marquardt fits of the force -> displacement surrogate (paper §3, eqs. 25-28) with Ceres, and the
// k-fold cross-validation that picks their orders (lambda, a, b). docs/SURROGATE.md §3 explains the model.
//
// For one contact node and one force axis j (x, y or z) the training data are the displacements of every
// surface node at signed force levels sigma_l along j. Two functions are fitted:
//  * eqs. 25-27, the stressed node:  u_i(sigma) = sum_{p=1..lambda} r_ip sigma^p, for the three components i
//    (the paper's diagonal i = j, plus the cross terms a curved surface has);
//  * eq. 28, the induced field:  u_i(X, sigma) = sum_{p=1..lambda} sigma^p sum_k c_ipk psi_k(xi, eta, zeta),
//  with
//    psi the surface-local polynomial of orders (a_i, b_i) plus contact terms of order c_i
//    (meshless/surrogate/surrogate_basis.hpp).
#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "meshless/surrogate/surrogate_basis.hpp"
#include "meshless/surrogate/surrogate_load_patch.hpp"

namespace meshless {

/// Knobs of the fits, with defaults; core::SurrogateSpec carries the ones a case sets.
struct SurrogateFitOptions {
  int max_force_order = 4;       ///< lambda tried: 1..max_force_order
  int max_tangential_order = 6;  ///< a tried: 0..max
  int max_normal_order = 2;      ///< b tried: 0..max
  int max_contact_order = 2;     ///< c tried: 0..max
  double contact_length = 0.0;   ///< [m] l of the contact terms (> 0 when max_contact_order > 0)
  int cv_folds = 5;              ///< k of the k-fold cross-validation
  unsigned cv_seed = 1;          ///< partition of the surface nodes into folds (deterministic)
  // Ceres Levenberg-Marquardt. The fitted problems are linear least squares in scaled units (O(1)
  // coefficients), so LM stops after a few iterations on the function tolerance.
  int max_num_iterations = 100;
  double function_tolerance = 1e-14;
  double gradient_tolerance = 1e-16;
  double parameter_tolerance = 1e-12;

  /// True when usable; otherwise `error` (if not null) says which field is wrong and what was expected.
  bool IsValid(std::string* error) const;
};

/// The full model's displacements for one contact node: for each axis j, one #S by 3 matrix per level [m].
struct ContactTrainingData {
  int contact = -1;            ///< index into SurfaceNodes
  std::vector<double> levels;  ///< signed force levels [N], the same for the three axes
  std::array<std::vector<core::PointMatrix>, 3> displacement;  ///< [axis][level], #S by 3
};

/// One cross-validated candidate and its error.
struct CvScore {
  int force_order = 0;       ///< lambda
  int tangential_order = 0;  ///< a (eq. 28 only)
  int normal_order = 0;      ///< b (eq. 28 only)
  int contact_order = 0;     ///< c (eq. 28 only)
  double rms = 0.0;          ///< RMS of the held-out errors [m]
};

/// What Ceres reported for one fit (ceres::Solver::Summary, kept for the surrogate file and the fit report).
struct FitSummary {
  std::string what;         ///< e.g. "eqs. 25-27 axis x" or "eq. 28 axis x component y power 2"
  std::string termination;  ///< CONVERGENCE, NO_CONVERGENCE, FAILURE, ...
  bool usable = false;
  int iterations = 0;
  double initial_cost = 0.0, final_cost = 0.0;  ///< in scaled units (0.5 sum r^2)
  int num_residuals = 0, num_parameters = 0;
};

/// Eq. 28 for one displacement component.
struct InducedFieldFit {
  int tangential_order = 0, normal_order = 0, contact_order = 0;  ///< a, b, c
  /// #basis by the axis' field_order: c_ipk, the coefficient of psi_k(X) sigma^p [m / N^p]
  Eigen::MatrixXd coefficients;
  double cv_rms = 0.0;        ///< cross-validation error of the chosen (a, b, c) [m]
  std::vector<CvScore> grid;  ///< every (a, b, c) tried
};

/// One force axis of one contact node.
struct AxisFit {
  int force_order = 0;                  ///< lambda_j of eqs. 25-27 (the contact node)
  Eigen::Matrix3Xd contact;             ///< 3 by lambda: r_ip of eqs. 25-27 [m / N^p]
  double contact_cv_rms = 0.0;          ///< cross-validation error of the chosen lambda [m]
  std::vector<CvScore> force_order_cv;  ///< every lambda tried
  /// The force order of eq. 28, chosen by its own cross-validation over the levels on every surface node: the
  /// field away from the contact need not be as (non)linear in the force as the contact node.
  int field_order = 0;
  double field_order_cv_rms = 0.0;  ///< [m]
  std::vector<CvScore> field_order_cv;
  std::array<InducedFieldFit, 3> field;  ///< per displacement component
  double training_rms = 0.0;  ///< eq. 28 against the training data over all surface nodes and levels [m]
};

struct ContactFit {
  int contact = -1;    ///< index into SurfaceNodes
  SurfaceFrame frame;  ///< the surface-local coordinates of eq. 28
  std::array<AxisFit, 3> axis;
  std::vector<FitSummary> summaries;
};

/// Fit eqs. 25-28 for one contact node. `max_force` [N] scales the forces (the trained range is
/// [-max_force, max_force]). Throws std::runtime_error when Ceres reports an unusable fit.
ContactFit fit_contact(const SurfaceNodes& surface, const ContactTrainingData& data, double max_force,
                       const SurrogateFitOptions& options);

/// The surrogate's surface nodes' per-node force polynomials of one axis (the eq. 28 functions evaluated at
/// the nodes): #S*3 by the axis' field_order, row 3s+i = component i of node s [m / N^p].
Eigen::MatrixXd nodal_coefficients(const SurfaceNodes& surface, const SurfaceFrame& frame,
                                   const AxisFit& axis);

}  // namespace meshless
