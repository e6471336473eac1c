#include "core/inadmissible_strain.hpp"

#include <fmt/format.h>

namespace core {
namespace {

double critical_principal_strain(const Vector6& strain, double k) {
  const Eigen::Vector3d lambda = KelvinLaw::principal_strains(strain);
  return k >= 0.0 ? lambda.minCoeff() : lambda.maxCoeff();
}

std::string describe(const std::string& model, double time, const Eigen::Vector3d& point,
                     const Vector6& strain, double k, double margin, double principal, double limit) {
  const Eigen::Vector3d mm = 1e3 * point;
  return fmt::format(
      "{}: at t = {:.6g} s the strain at ({:.2f}, {:.2f}, {:.2f}) mm left the admissible range of the "
      "adjustment "
      "function N(eps) = eps + k eps.eps (k = {:g}): its {} principal strain is {:.4f}, beyond the limit "
      "-1/(2k) = {:.4f}, so 1 + 2k lambda = {:.3g} <= 0 (strain xx, yy, zz, gamma_xy, gamma_yz, gamma_zx = "
      "{:.4f}, {:.4f}, {:.4f}, {:.4f}, {:.4f}, {:.4f}). There the material tangent is singular and no "
      "equilibrium "
      "exists past it; a smaller time step does not change that. To stay inside the range: lower the force "
      "(/load/force), lower |k| (/material/k), or spread the force over a larger patch (/load/radius); a "
      "pointed "
      "or thin part of the surface under the probe concentrates the strain (docs/MATERIAL.md, admissible "
      "range). Where the strain concentrates at a singular line that refinement resolves (a crack's front, a "
      "clamp's edge), /material/slope_floor continues the law past its limit instead (docs/MATERIAL.md §1.7)",
      model, time, mm.x(), mm.y(), mm.z(), k, k > 0.0 ? "smallest" : "largest", principal, limit, margin,
      strain[0], strain[1], strain[2], strain[3], strain[4], strain[5]);
}

}  // namespace

InadmissibleStrain::InadmissibleStrain(const std::string& model, double time, const Eigen::Vector3d& point,
                                       const Vector6& strain, const KelvinLaw& law)
    : std::runtime_error(describe(model, time, point, strain, law.parameters().k,
                                  law.admissibility_margin(strain),
                                  critical_principal_strain(strain, law.parameters().k), law.limit_strain())),
      model_(model),
      time_(time),
      point_(point),
      strain_(strain),
      k_(law.parameters().k),
      margin_(law.admissibility_margin(strain)),
      principal_(critical_principal_strain(strain, law.parameters().k)),
      limit_(law.limit_strain()) {}

}  // namespace core
