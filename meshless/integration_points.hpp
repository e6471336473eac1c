#pragma once
// Integration points of the EFG weak form with their MLS shape functions, tabulated once (the node cloud and
// the background cells do not move: small-strain kinematics, eq. 17), so every Newton iteration of every time
// step reuses phi and dphi instead of re-solving the moment matrix of eq. 3.
#include <Eigen/Core>
#include <vector>

#include "core/tet_mesh.hpp"

namespace meshless {

class MlsShapeFunctions;

/// Shape-function values at a set of points, in compressed-row layout: the nodes of point q are
/// nodes[offsets[q] .. offsets[q+1]), ascending, with phi and dphi in the same slots.
struct ShapeTable {
  core::PointMatrix points;     ///< #q by 3 [m]
  Eigen::VectorXd weights;      ///< #q quadrature weights [m^3] (volume) or [m^2] (surface)
  std::vector<int> cells;       ///< #q: background tetrahedron (volume) or boundary face (surface) index
  std::vector<int> offsets;     ///< #q + 1
  std::vector<int> nodes;       ///< offsets.back()
  std::vector<double> phi;      ///< offsets.back(), phi_i(X_q)
  Eigen::Matrix3Xd dphi;        ///< 3 by offsets.back(), grad phi_i(X_q) [1/m]; 3 by 0 without gradients

  int size() const { return static_cast<int>(weights.size()); }
  int begin(int q) const { return offsets[q]; }
  int end(int q) const { return offsets[q + 1]; }
  bool has_gradients() const { return dphi.cols() > 0; }
};

/// Gauss points of every background tetrahedron (rule of `order`, see tet_rule()).
/// @param[out] points #q by 3, weights #q (|J| included), cells #q
void tet_quadrature_points(const core::TetMesh& mesh, int order, core::PointMatrix* points,
                           Eigen::VectorXd* weights, std::vector<int>* cells);

/// Gauss points of every boundary triangle (rule of `order`, see triangle_rule()).
void face_quadrature_points(const core::TetMesh& mesh, int order, core::PointMatrix* points,
                            Eigen::VectorXd* weights, std::vector<int>* faces);

/// Evaluate the MLS shape functions at every point (in parallel when OpenMP is available).
/// @throws SingularMomentMatrix (from MlsShapeFunctions) naming the first failing point and its neighbour count
ShapeTable tabulate_shape_functions(const MlsShapeFunctions& mls, core::PointMatrix points, Eigen::VectorXd weights,
                                    std::vector<int> cells, bool with_gradients);

/// The transpose of a ShapeTable's node lists: for node i, the table slots (entries of nodes/phi/dphi) where it
/// appears, and the point each slot belongs to. Lets assembly run row by row (one node's equations at a time),
/// which needs no locks between threads.
struct NodeIncidence {
  std::vector<int> offsets;  ///< #nodes + 1
  std::vector<int> slots;    ///< slot into the table's nodes/phi/dphi arrays
  std::vector<int> points;   ///< the table point owning that slot
  NodeIncidence() = default;
  NodeIncidence(const ShapeTable& table, int num_nodes);
};

}  // namespace meshless
