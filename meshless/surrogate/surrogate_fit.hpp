#pragma once
// Fits of the force -> displacement surrogate (paper §3, eqs. 25-28) and the k-fold cross-validation that
// picks their orders (lambda, a, b, c). docs/SURROGATE.md §3 explains the model.
//
// For one contact node and one force axis j (x, y or z) the training data are the displacements of every
// surface node at signed force levels sigma_l along j. Two functions are fitted:
//  * eqs. 25-27, the stressed node:  u_i(sigma) = sum_{p=1..lambda} r_ip sigma^p, for the three components i
//    (the paper's diagonal i = j, plus the cross terms a curved surface has);
//  * eq. 28, the induced field:  u_i(X, sigma) = sum_{p=1..lambda} sigma^p sum_k c_ipk psi_k(xi, eta, zeta),
//  with
//    psi the surface-local polynomial of orders (a_i, b_i) plus contact terms of order c_i
//    (meshless/surrogate/surrogate_basis.hpp).
// Both are linear in their coefficients, so every fit is a linear least-squares problem, solved directly by
// ScaledLeastSquares (column-scaled, rank-revealing QR): it cannot fail, and a term the data cannot determine
// is dropped instead of failing the surrogate (docs/SURROGATE.md §3, "Why linear least squares").
#include <Eigen/Core>
#include <Eigen/QR>
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
  /// Data below this fraction of the axis' largest trained displacement are noise: a component (eqs. 25-27 at
  /// the contact node, or eq. 28 over the surface) or a force power of eq. 28 whose data all lie below it is
  /// fitted as zero, and cross-validation errors below it count as equal (the smallest model wins). The full
  /// model solves to a relative Newton residual of 1e-8 (EfgOptions::newton_tolerance), so a response below
  /// 1e-7 of the main one is not resolved by the training; the thread count moves the training data by far
  /// less (3e-16 on the lung, docs/SURROGATE.md §3).
  double noise_floor = 1e-7;
  /// Rank threshold of the QR with column pivoting, on unit-norm columns: a pivot below this fraction of the
  /// largest one marks its column as (numerically) a combination of the columns before it, and the column is
  /// dropped (coefficient 0). ScaledLeastSquares.
  double rank_threshold = 1e-10;

  /// True when usable; otherwise `error` (if not null) says which field is wrong and what was expected.
  bool IsValid(std::string* error) const;
};

/// min ||A X - B|| (Frobenius) for every column of B at once, by Householder QR with column pivoting of A
/// with its columns scaled to unit norm. Scaling first makes the pivots comparable (a column of s^4 or xi^6
/// is not mistaken for a dependent one because its values are small), so the rank the pivots reveal is a
/// property of the basis, not of its units. Columns whose pivot is at most `rank_threshold` times the
/// largest, and zero columns, are dropped: their rows of X are exactly 0 (the basic solution). The solve is
/// direct and cannot fail; when B is exactly zero, X is exactly zero.
class ScaledLeastSquares {
 public:
  ScaledLeastSquares(const Eigen::MatrixXd& a, double rank_threshold);
  /// A.cols() by B.cols(); `b` has A.rows() rows.
  Eigen::MatrixXd solve(const Eigen::MatrixXd& b) const;
  int rank() const { return static_cast<int>(rank_); }
  int cols() const { return static_cast<int>(inverse_scale_.size()); }

 private:
  Eigen::VectorXd inverse_scale_;  ///< 1 / |column|, 0 for a zero column
  Eigen::Index rows_ = 0;
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr_;  ///< of the scaled columns
  Eigen::Index rank_ = 0;
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

/// How one fit went (kept for the surrogate file, `contacts[].ceres_summaries`, and the fit report).
struct FitSummary {
  std::string what;  ///< e.g. "eqs. 25-27 axis x" or "eq. 28 axis x component y power 2"
  /// SOLVED (the linear least-squares solution) or BELOW_NOISE_FLOOR (the data are noise: fitted as zero).
  /// Files fitted before the linear solve hold Ceres' terminations (CONVERGENCE, ...).
  std::string termination;
  bool usable = false;
  int iterations = 0;                           ///< 0: a direct solve (Ceres' count in older files)
  double initial_cost = 0.0, final_cost = 0.0;  ///< in scaled units (0.5 sum r^2): at zero, at the solution
  int num_residuals = 0, num_parameters = 0;
  int rank = -1;  ///< columns kept by the rank-revealing QR (-1: not recorded, older files)
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
/// [-max_force, max_force]). Throws std::invalid_argument on inconsistent input or too few levels or nodes
/// for the cross-validation; the fits themselves cannot fail (a component of noise gets zero coefficients).
ContactFit fit_contact(const SurfaceNodes& surface, const ContactTrainingData& data, double max_force,
                       const SurrogateFitOptions& options);

/// L by order matrix of s_l^p, p = 1..order: the force powers of eqs. 25-28 (no constant: u(0) = 0).
Eigen::MatrixXd force_powers(const std::vector<double>& s, int order);

/// The surrogate's surface nodes' per-node force polynomials of one axis (the eq. 28 functions evaluated at
/// the nodes): #S*3 by the axis' field_order, row 3s+i = component i of node s [m / N^p].
Eigen::MatrixXd nodal_coefficients(const SurfaceNodes& surface, const SurfaceFrame& frame,
                                   const AxisFit& axis);

}  // namespace meshless
