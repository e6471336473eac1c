#pragma once
// The error both models raise when a strain leaves the admissible range of the adjustment function
// N(eps) = eps + k eps.eps (docs/MATERIAL.md §1.5): some principal strain lambda reached -1/(2k), where the
// consistent tangent is singular and past which no equilibrium exists. Newton cannot fix that and a smaller
// step does not either, so the models stop at once with this exception instead of cutting the step back.
#include <Eigen/Core>
#include <stdexcept>
#include <string>

#include "core/kelvin_law.hpp"

namespace core {

class InadmissibleStrain : public std::runtime_error {
 public:
  /// @param model  which model met it ("meshless (EFG)", "FEM reference"), for the message
  /// @param time   t_{n+1} of the step being solved [s]
  /// @param point  the integration point [m] (the message reports mm)
  /// @param strain the engineering Voigt strain there
  /// @param law    the law whose k sets the limit
  InadmissibleStrain(const std::string& model, double time, const Eigen::Vector3d& point,
                     const Vector6& strain, const KelvinLaw& law);

  const std::string& model() const { return model_; }
  double time() const { return time_; }                    ///< [s]
  const Eigen::Vector3d& point() const { return point_; }  ///< [m]
  const Vector6& strain() const { return strain_; }        ///< engineering Voigt
  double k() const { return k_; }
  double margin() const { return margin_; }               ///< min_i 1 + 2 k lambda_i (<= 0)
  double principal_strain() const { return principal_; }  ///< the lambda_i that set the margin
  double limit_strain() const { return limit_; }          ///< -1/(2k)

 private:
  std::string model_;
  double time_;
  Eigen::Vector3d point_;
  Vector6 strain_;
  double k_, margin_, principal_, limit_;
};

}  // namespace core

namespace core {

/// The smallest admissibility margin min_i (1 + 2 k lambda_i) a model met in its converged states, and where:
/// how close a run came to the limit (reported in timings.json).
struct SmallestMargin {
  double margin = 1.0;                              ///< 1 when k = 0 or before the first step
  double time = 0.0;                                ///< [s]
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  ///< [m]
  Vector6 strain = Vector6::Zero();                 ///< engineering Voigt

  void update(double m, double t, const Eigen::Vector3d& x, const Vector6& e) {
    if (!(m < margin)) return;
    margin = m;
    time = t;
    point = x;
    strain = e;
  }
};

}  // namespace core
