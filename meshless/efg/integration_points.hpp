#pragma once
// Integration points of the EFG weak form with their MLS shape functions, tabulated once (the node cloud and
// the background cells do not move: small-strain kinematics, eq. 17), so every Newton iteration of every time
// step reuses phi and dphi instead of re-solving the moment matrix of eq. 3.
//
// With a cut (paper §4) the background cells and the boundary faces that the cut crosses are split into pieces
// (meshless/cut/cut_quadrature.hpp), and both lips of the cut get boundary points of their own: the divergence
// identity, the VCI correction and any lip traction integrate over them like over the outer surface.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/ruled_surface.hpp"
#include "core/tet_mesh.hpp"

namespace meshless {

class MlsShapeFunctions;

/// A set of integration points before their shape functions are known.
struct QuadraturePoints {
  core::PointMatrix points;        ///< #q by 3 [m]
  Eigen::VectorXd weights;         ///< #q quadrature weights [m^3] (volume) or [m^2] (surface)
  /// #q: the background tetrahedron (volume points and lip points) or the boundary face (outer-surface points)
  std::vector<int> cells;
  /// #q: the side of the cut a point on it is evaluated on (+1 or -1: a lip point), 0 elsewhere
  std::vector<std::int8_t> sides;
  Eigen::Matrix3Xd normals;        ///< 3 by #q outward unit normals (surface points); 3 by 0 for volume points

  int size() const { return static_cast<int>(weights.size()); }
  bool on_lip(int q) const { return sides[q] != 0; }
  /// Append another set (both volume, or both surface).
  void append(const QuadraturePoints& other);
};

/// Gauss points of every background tetrahedron (rule of `order`, see tet_rule()); a tetrahedron that `cut`
/// crosses (when not null) is split along the crossing panels' planes and each piece gets the rule.
QuadraturePoints volume_quadrature(const core::TetMesh& mesh, int order, const core::RuledSurface* cut = nullptr);

/// Gauss points of every boundary triangle (rule of `order`, see triangle_rule()), with the face's outward normal;
/// a face that `cut` crosses (when not null) is split along the crossing panels' planes.
QuadraturePoints boundary_quadrature(const core::TetMesh& mesh, int order, const core::RuledSurface* cut = nullptr);

/// Gauss points on both lips of the cut inside the body (the cut clipped to every background tetrahedron it
/// crosses), each point twice: on the s > 0 lip (side +1, outward normal -n) and on the s < 0 lip (side -1,
/// outward normal +n), n the panel normal; cells = the tetrahedron.
QuadraturePoints lip_quadrature(const core::TetMesh& mesh, int order, const core::RuledSurface& cut);

/// Shape-function values at a set of points. The nodes of point q sit in the slots [begin(q), end(q)) of nodes,
/// phi and dphi, ascending. A table made from scratch stores its rows one after another. A local update (the cut
/// advanced, paper §4) keeps every row it reuses where it is, writes the rows it evaluates again into spare slots
/// after the last one in use, and retires the slots of the rows they replace: so iterate rows through begin/end,
/// never the slot arrays whole. When the spare slots run out, the update packs the rows into new arrays.
struct ShapeTable {
  core::PointMatrix points;     ///< #q by 3 [m]
  Eigen::VectorXd weights;      ///< #q quadrature weights [m^3] (volume) or [m^2] (surface)
  std::vector<int> cells;       ///< #q, as QuadraturePoints::cells
  std::vector<std::int8_t> sides;  ///< #q, as QuadraturePoints::sides
  Eigen::Matrix3Xd normals;     ///< as QuadraturePoints::normals
  std::vector<int> row_begin;   ///< #q: the first slot of point q
  std::vector<int> row_end;     ///< #q: one past its last slot
  std::vector<int> nodes;       ///< per slot: the node; nodes.size() is the capacity
  std::vector<double> phi;      ///< per slot: phi_i(X_q)
  Eigen::Matrix3Xd dphi;        ///< 3 by capacity: grad phi_i(X_q) [1/m]; 3 by 0 without gradients
  int slots_used = 0;           ///< slots [0, slots_used) hold rows or retired rows; the rest are spare
  bool gradients = false;       ///< whether dphi is tabulated

  int size() const { return static_cast<int>(weights.size()); }
  int begin(int q) const { return row_begin[q]; }
  int end(int q) const { return row_end[q]; }
  bool has_gradients() const { return gradients; }
  bool on_lip(int q) const { return sides[q] != 0; }
  /// The (point, node) entries of all rows: the slots in use less the retired ones.
  long long num_entries() const;
};

/// Evaluate the MLS shape functions at every point (in parallel when OpenMP is available), each with its side hint.
/// `spare_fraction` of the entries is kept as spare slots for local updates (0 for a body without a cut).
/// @throws SingularMomentMatrix (from MlsShapeFunctions) naming the first failing point and its neighbour count
ShapeTable tabulate_shape_functions(const MlsShapeFunctions& mls, QuadraturePoints points, bool with_gradients,
                                    double spare_fraction = 0.0);

/// What a local update of a table did.
struct TableUpdate {
  int rows_evaluated = 0;  ///< points whose shape functions were evaluated again
  bool packed = false;     ///< the spare slots ran out and the rows were packed into new arrays
};

/// A local update in place: `table` now holds the shape functions of `points`, where point q reuses row reuse[q]
/// of the table as it was (when >= 0: the row is kept in its slots, not copied) and is evaluated otherwise.
/// `spare_fraction` is the spare room kept if the rows have to be packed. The table's gradient setting is kept.
/// @throws SingularMomentMatrix as above; the table is then unchanged
TableUpdate update_shape_functions(const MlsShapeFunctions& mls, QuadraturePoints points, const std::vector<int>& reuse,
                                   double spare_fraction, ShapeTable* table);

/// The transpose of a ShapeTable's node lists: for node i, the table slots (entries of nodes/phi/dphi) where it
/// appears, and the point each slot belongs to. Lets assembly run row by row (one node's equations at a time),
/// which needs no locks between threads.
struct NodeIncidence {
  std::vector<int> offsets;  ///< #nodes + 1
  std::vector<int> slots;    ///< slot into the table's nodes/phi/dphi arrays
  std::vector<int> points;   ///< the table point owning that slot
  int num_points = 0;        ///< the table's point count
  NodeIncidence() = default;
  NodeIncidence(const ShapeTable& table, int num_nodes);
  /// The same as NodeIncidence(table, num_nodes) after a local update that kept its rows in place
  /// (update_shape_functions without packing; `reuse` as given to it), built from the incidence `before` the update
  /// instead of transposing the whole table: a kept row's entries keep their slots and take the point's new
  /// number; the evaluated rows' entries are merged in. That needs the kept rows in the order they had (reuse
  /// increasing over them), which holds since the quadrature is built cell by cell; otherwise it transposes the
  /// table.
  NodeIncidence(const NodeIncidence& before, const ShapeTable& table, const std::vector<int>& reuse);
};

/// The same as NodeIncidence(before, table, reuse), written into `merged` (not `before`), whose arrays are reused
/// when they are large enough: a local update that keeps the incidence before last for this allocates nothing.
/// `dropped_entries` (optional, #nodes): per node, the entries of `before` whose rows no point reuses (the caller
/// counted them from the dropped rows before the update), which spares a pass over every entry; a count that
/// disagrees with the entries found makes the result a transpose of the table instead.
void merge_incidence(const NodeIncidence& before, const ShapeTable& table, const std::vector<int>& reuse,
                     NodeIncidence* merged, const std::vector<int>* dropped_entries = nullptr);

}  // namespace meshless
