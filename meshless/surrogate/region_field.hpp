#pragma once
// Eq. 28 over a contact region, with the contact position as a variable (docs/SURROGATE.md §4, "A contact
// region"). One fit covers every trained contact of the region:
//
//   u_i(X; p, sigma_j) = sum_{m=1..lambda'} sigma_j^m sum_k sum_q C_ijm[k, q] psi_k(X; p) T_q(p)
//
// psi_k is the spatial basis of surrogate_basis.hpp in the REGION's frame (the centre node's), with its
// polynomial terms at X (how the whole body follows the load) and its contact terms at X - p (the dent, which
// moves with the probe); T_q(p) are the monomials of degree <= position_order of p's coordinates in the
// region's tangent plane (t = in-plane offset / radius). The model is linear in C, so it is fitted by
// ScaledLeastSquares over all contacts, nodes and levels at once. A query at any p of the region evaluates one
// field with one dent at p.
//
// Why not interpolate the per-contact fits: their polynomial and contact terms nearly span the same functions
// on a body the size of a few contact lengths, so each fit splits its field into two large parts that cancel
// (40 times the field on the test box). Moving one part and not the other, or blending whole fields (two
// half-dents), left 30-40 % and 7-8 % errors at untrained nodes of the box; fitting the position as a
// variable never splits the field.
//
// Units: SI (m, N). Lifetime and threads: a RegionFieldEvaluator is immutable after construction; evaluate()
// is const, allocates nothing and may run from several threads at once, each with its own output.
#include <Eigen/Core>
#include <array>
#include <vector>

#include "meshless/surrogate/contact_region.hpp"
#include "meshless/surrogate/surrogate_fit.hpp"

namespace meshless {

/// One force axis of the region's field.
struct RegionAxisField {
  int field_order = 0;  ///< lambda' (force powers 1..lambda')
  /// Per displacement component: the orders (a, b, c) and the coefficients, (#basis * #position monomials) by
  /// field_order, row k * #position monomials + q [m / N^p]; cv_rms and grid are unused here.
  std::array<InducedFieldFit, 3> field;
};

struct RegionField {
  SurfaceFrame frame;      ///< the centre node's frame: the polynomial's coordinates and the contact terms' axes
  double radius = 0.0;     ///< [m] divides the position's in-plane coordinates
  int position_order = 0;  ///< degree of the position monomials T_q: 0, 1 or 2
  std::array<RegionAxisField, 3> axis;
  double training_rms = 0.0;  ///< [m] over every contact, node, level and axis of the training data
};

/// Number of monomials of degree <= order in two variables: 1, 3, 6.
int position_monomials(int order);
/// T_q(p): 1, t1, t2, t1^2, t1 t2, t2^2 (as many as the order has), into `out`.
void position_basis(const RegionField& field, const Eigen::Vector3d& point, double* out);

/// Fit the region's field on the trained contacts' data (one ContactTrainingData per contact, the same levels).
/// `shape` gives each axis' field order and each component's orders (a, b, c): the largest the contacts' own
/// cross-validated fits chose (region_shape()). Throws std::invalid_argument on inconsistent input or fewer
/// contacts than position monomials.
RegionField fit_region_field(const SurfaceNodes& surface, const ContactRegion& region,
                             const std::vector<ContactTrainingData>& data, double max_force,
                             const std::array<RegionAxisField, 3>& shape, int position_order,
                             const SurrogateFitOptions& options);

/// The orders of the region's field: per axis the largest lambda', per component the largest (a, b, c) that the
/// contacts' own fits chose.
std::array<RegionAxisField, 3> region_shape(const std::vector<ContactFit>& fits);

/// The region's field evaluated at the surface nodes, precomputed for real-time queries.
class RegionFieldEvaluator {
 public:
  RegionFieldEvaluator(RegionField field, const core::PointMatrix& surface_position);
  const RegionField& field() const { return field_; }
  /// u at every surface node for a probe at `point` [m] with `force` [N] (each component within the trained
  /// range), into `u` (3 #S values, node s component i at 3 s + i) [m].
  void evaluate(const Eigen::Vector3d& point, const Eigen::Vector3d& force, double* u) const;
  /// The field at a fixed probe point as per-node force polynomials: 3 #S by columns(), column (j, m) (axes in
  /// order, m = 1..lambda'_j) the coefficient of sigma_j^m [m / N^m]. Not for the real-time loop (it allocates).
  Eigen::MatrixXd nodal_at(const Eigen::Vector3d& point) const;
  /// Number of force powers: sum over axes of lambda'.
  int force_columns() const;

 private:
  /// The field for force powers `powers` (force_columns() values, sigma_j^m in the order of nodal_at()).
  void evaluate_powers(const Eigen::Vector3d& point, const double* powers, double* u) const;

  RegionField field_;
  core::PointMatrix position_;
  int columns_ = 0;         ///< sum over axes of lambda' * #position monomials
  Eigen::MatrixXd smooth_;  ///< 3 #S by columns_: the polynomial terms at the nodes
  std::array<Eigen::MatrixXd, 3> dent_;  ///< per component: its contact terms by columns_
  int contact_order_ = 0;                ///< the largest c of the components
};

}  // namespace meshless
