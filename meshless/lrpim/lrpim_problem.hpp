#pragma once
// What the LRPIM model solves: a node cloud in a box body, the boundary conditions per face, the Kelvin law and
// the step times (docs/LRPIM.md). The same problem class as the EFG's verification problems (meshless/efg/
// efg_problem.hpp), without the background mesh: only the nodes are used.
#include <array>
#include <functional>
#include <string>
#include <vector>

#include "core/kelvin_law.hpp"
#include "core/tet_mesh.hpp"
#include "meshless/lrpim/box_body.hpp"
#include "meshless/lrpim/local_quadrature.hpp"
#include "meshless/lrpim/rpim_shape_functions.hpp"

namespace meshless::lrpim {

/// The condition on one face of the box.
enum class FaceCondition {
  free_surface,  ///< t = 0: no term (the natural condition)
  traction,      ///< t = load_scale(t) * traction(X), through the local boundary integral
  displacement,  ///< u = prescribed_displacement(X): nodal values set (Kronecker delta), and the unknown
                 ///< reaction sigma n integrated on the local boundary of the nodes whose sphere reaches it
};

struct LrpimProblem {
  std::string name = "lrpim";
  core::PointMatrix nodes;  ///< #nodes by 3 [m]; boundary nodes must lie on the faces to 1e-9 of the spacing
  BoxBody body;
  std::array<FaceCondition, kBoxFaces> faces{};  ///< -x, +x, -y, +y, -z, +z
  std::function<Eigen::Vector3d(const Eigen::Vector3d&)> prescribed_displacement;  ///< [m], held in time
  std::function<Eigen::Vector3d(const Eigen::Vector3d&)> traction;                 ///< [Pa]
  std::function<double(double)> load_scale;  ///< factor on the traction at time t; empty: 1 (a step load)
  core::KelvinParameters material;
  /// Times of the steps [s]. The first step goes from t = 0 to step_times[0]; step_times[0] = 0 is the
  /// instantaneous (dt = 0) elastic step, as in the EFG and FEM models.
  std::vector<double> step_times = {0.0};
  double node_spacing = 0.0;  ///< d_c [m]: scales the MQ shape parameter and r_q
  RpimParameters rpim;
  double alpha_q = 1.5;  ///< r_q = alpha_q * node_spacing, the radius of each node's local sub-domain
  LocalQuadratureRule rule;
  /// Correct each node's test gradient by a constant so that the local divergence identity
  /// int_{Omega_s} grad v dV = int_{boundary of Omega_s in dOmega} v n dA holds for the quadrature (the linear
  /// variationally consistent correction of Chen, Hillman & Rueter 2013, which the EFG applies to its test
  /// functions, here per local domain). Without it the clipped spheres' angular quadrature error breaks the
  /// patch test at ~1e-3 (docs/LRPIM.md §4).
  bool divergence_correction = true;
};

}  // namespace meshless::lrpim
