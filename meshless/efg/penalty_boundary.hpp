#pragma once
// Boundary terms of the EFG weak form (eq. 19) on the tabulated boundary points:
//  * penalty essential BC (eq. 23): K^alpha_ij = int_Gu phi_i alpha phi_j dGamma I3 and its load
//    alpha int_Gu phi_i u-bar dGamma (the u-bar part of the last term of eq. 24);
//  * traction (eq. 24): int_Gt phi_i t-bar dGamma (and, for verification, a traction on the lips of a cut).
#include <Eigen/Core>
#include <vector>

#include "meshless/efg/efg_problem.hpp"
#include "meshless/efg/integration_points.hpp"

namespace meshless {

/// Per boundary point: the weights of eqs. 23-24 and the data they multiply.
struct BoundaryTerms {
  std::vector<double> penalty_weight;   ///< #q: alpha * w_q on penalised faces, 0 elsewhere
  std::vector<double> traction_weight;  ///< #q: w_q on loaded faces, 0 elsewhere
  Eigen::VectorXd penalty_load;         ///< 3N: alpha int_Gu phi_i u-bar
  Eigen::VectorXd traction_load;        ///< 3N: int_Gt phi_i t-bar at full load (times load_scale(t))
  double penalised_area = 0.0;          ///< [m^2]
  double loaded_area = 0.0;             ///< [m^2]
  double largest_alpha = 0.0;           ///< [Pa/m] the largest alpha on a penalised face (k_s of an elastic support)
};

/// Build the boundary terms from the face roles of `problem` (masks, or face_tags fixed/load); lip points carry
/// problem.lip_traction when it is set and nothing else.
/// @param surface boundary points of the outer faces (cells = face index) and of the lips, with phi
BoundaryTerms make_boundary_terms(const EfgProblem& problem, const ShapeTable& surface, double alpha);

}  // namespace meshless
