#pragma once
// Ceres residuals of the surrogate's fits (paper §3), fitted with Levenberg-Marquardt
// (meshless/surrogate/surrogate_fit.hpp). Each functor is templated for automatic differentiation; Create() hides the
// dynamic sizes.
//
// Scaling: forces enter as s = sigma / max_force (in [-1, 1]) and displacements as u / u_scale, so the
// coefficients are O(1) and Ceres' absolute tolerances mean the same for every case; the caller converts the
// coefficients back to SI (m / N^p).
#include <ceres/ceres.h>

#include <vector>

namespace meshless {

/// Eqs. 25-27 for one displacement component of one node under one force axis:
///     u(s) = r_1 s + r_2 s^2 + ... + r_lambda s^lambda
/// The paper's constant r_0 is dropped: the body starts undeformed, so u(0) = 0 exactly (docs/SURROGATE.md
/// §3). One residual per trained force level; parameters: the lambda coefficients r_1..r_lambda.
class ForcePolynomialResidual {
 public:
  ForcePolynomialResidual(double scaled_force, double scaled_displacement, int order)
      : s_(scaled_force), u_(scaled_displacement), order_(order) {}

  template <typename T>
  bool operator()(T const* const* parameters, T* residual) const {
    const T* r = parameters[0];
    T power = T(s_);
    T sum = T(0.0);
    for (int p = 0; p < order_; ++p) {
      sum += r[p] * power;
      power *= s_;
    }
    residual[0] = sum - u_;
    return true;
  }

  static ceres::CostFunction* Create(double scaled_force, double scaled_displacement, int order) {
    auto* cost = new ceres::DynamicAutoDiffCostFunction<ForcePolynomialResidual, 8>(
        new ForcePolynomialResidual(scaled_force, scaled_displacement, order));
    cost->AddParameterBlock(order);
    cost->SetNumResiduals(1);
    return cost;
  }

 private:
  double s_, u_;
  int order_;
};

/// Eq. 28 for one displacement component, one force power p and one surface node X: the spatial surface
/// function
///     c_p(X) = sum_k c_pk psi_k(xi, eta, zeta)
/// against that node's own coefficient of s^p (the per-node fit of eqs. 25-27 over all trained levels;
/// fitting the two stages in turn is the joint least-squares fit, because the design is the Kronecker product
/// of the force powers and the spatial basis: docs/SURROGATE.md §3). Parameters: the #basis coefficients c_p.
class InducedFieldResidual {
 public:
  /// @param basis psi_k(X) of this node, #basis values (copied)
  InducedFieldResidual(std::vector<double> basis, double target) : psi_(std::move(basis)), target_(target) {}

  template <typename T>
  bool operator()(T const* const* parameters, T* residual) const {
    const T* c = parameters[0];
    T sum = T(0.0);
    for (std::size_t k = 0; k < psi_.size(); ++k) sum += c[k] * psi_[k];
    residual[0] = sum - target_;
    return true;
  }

  static ceres::CostFunction* Create(std::vector<double> basis, double target) {
    const int n = static_cast<int>(basis.size());
    auto* cost = new ceres::DynamicAutoDiffCostFunction<InducedFieldResidual, 16>(
        new InducedFieldResidual(std::move(basis), target));
    cost->AddParameterBlock(n);
    cost->SetNumResiduals(1);
    return cost;
  }

 private:
  std::vector<double> psi_;
  double target_;
};

}  // namespace meshless
