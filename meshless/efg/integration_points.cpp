#include "meshless/efg/integration_points.hpp"

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "meshless/cut/cut_quadrature.hpp"
#include "meshless/efg/gauss_quadrature_tet.hpp"
#include "meshless/mls/mls_shape_functions.hpp"
#include "meshless/parallel_for.hpp"

namespace meshless {
namespace {

/// Growable point set: rows are pushed one at a time, then packed into QuadraturePoints.
struct PointBuffer {
  std::vector<Eigen::Vector3d> points, normals;
  std::vector<double> weights;
  std::vector<int> cells;
  std::vector<std::int8_t> sides;

  void add(const Eigen::Vector3d& x, double w, int cell, int side, const Eigen::Vector3d* normal = nullptr) {
    points.push_back(x);
    weights.push_back(w);
    cells.push_back(cell);
    sides.push_back(static_cast<std::int8_t>(side));
    if (normal) normals.push_back(*normal);
  }
  void add_tet(const TetVertices& t, const SimplexRule& rule, int cell) {
    Eigen::Matrix3d j;  // affine map X = t0 + J xi
    for (int c = 0; c < 3; ++c) j.col(c) = t[c + 1] - t[0];
    const double det = std::abs(j.determinant());
    for (int q = 0; q < rule.size(); ++q) add(t[0] + j * rule.points[q], rule.weights[q] * det, cell, 0);
  }
  void add_triangle(const TriangleVertices& t, const SimplexRule& rule, int cell, int side, const Eigen::Vector3d& n) {
    const Eigen::Vector3d e1 = t[1] - t[0], e2 = t[2] - t[0];
    const double two_area = e1.cross(e2).norm();
    for (int q = 0; q < rule.size(); ++q)
      add(t[0] + rule.points[q].x() * e1 + rule.points[q].y() * e2, rule.weights[q] * two_area, cell, side, &n);
  }
  QuadraturePoints pack(bool with_normals) const {
    QuadraturePoints out;
    const Eigen::Index n = static_cast<Eigen::Index>(points.size());
    out.points.resize(n, 3);
    out.weights.resize(n);
    for (Eigen::Index q = 0; q < n; ++q) {
      out.points.row(q) = points[q].transpose();
      out.weights[q] = weights[q];
    }
    out.cells = cells;
    out.sides = sides;
    out.normals.resize(3, with_normals ? n : 0);
    if (with_normals)
      for (Eigen::Index q = 0; q < n; ++q) out.normals.col(q) = normals[q];
    return out;
  }
};

TetVertices tet_of(const core::TetMesh& mesh, int t) {
  TetVertices v;
  for (int k = 0; k < 4; ++k) v[k] = mesh.vertices.row(mesh.tets(t, k)).transpose();
  return v;
}

}  // namespace

void QuadraturePoints::append(const QuadraturePoints& other) {
  const Eigen::Index n = size(), m = other.size();
  points.conservativeResize(n + m, 3);
  points.bottomRows(m) = other.points;
  weights.conservativeResize(n + m);
  weights.tail(m) = other.weights;
  cells.insert(cells.end(), other.cells.begin(), other.cells.end());
  sides.insert(sides.end(), other.sides.begin(), other.sides.end());
  if (other.normals.cols() > 0 || normals.cols() > 0) {
    normals.conservativeResize(3, n + m);
    normals.rightCols(m) = other.normals;
  }
}

QuadraturePoints volume_quadrature(const core::TetMesh& mesh, int order, const core::RuledSurface* cut) {
  const SimplexRule rule = tet_rule(order);
  PointBuffer buffer;
  for (int t = 0; t < mesh.num_tets(); ++t) {
    const TetVertices tet = tet_of(mesh, t);
    const std::vector<int> panels = cut ? panels_crossing_tet(*cut, tet) : std::vector<int>{};
    if (panels.empty()) {
      buffer.add_tet(tet, rule, t);
      continue;
    }
    for (const TetVertices& piece : split_tet(*cut, panels, tet)) buffer.add_tet(piece, rule, t);
  }
  return buffer.pack(false);
}

QuadraturePoints boundary_quadrature(const core::TetMesh& mesh, int order, const core::RuledSurface* cut) {
  const SimplexRule rule = triangle_rule(order);
  PointBuffer buffer;
  for (int f = 0; f < mesh.boundary_faces.rows(); ++f) {
    TriangleVertices tri;
    for (int k = 0; k < 3; ++k) tri[k] = mesh.vertices.row(mesh.boundary_faces(f, k)).transpose();
    const Eigen::Vector3d normal = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalized();  // outward: right-hand rule
    const std::vector<int> panels = cut ? panels_crossing_triangle(*cut, tri) : std::vector<int>{};
    if (panels.empty()) {
      buffer.add_triangle(tri, rule, f, 0, normal);
      continue;
    }
    for (const TriangleVertices& piece : split_triangle(*cut, panels, tri)) buffer.add_triangle(piece, rule, f, 0, normal);
  }
  return buffer.pack(true);
}

QuadraturePoints lip_quadrature(const core::TetMesh& mesh, int order, const core::RuledSurface& cut) {
  const SimplexRule rule = triangle_rule(order);
  PointBuffer buffer;
  std::vector<std::vector<Eigen::Vector3d>> polygons;
  for (int t = 0; t < mesh.num_tets(); ++t) {
    const std::vector<int> panels = panels_crossing_tet(cut, tet_of(mesh, t), &polygons);
    for (std::size_t k = 0; k < panels.size(); ++k) {
      const Eigen::Vector3d n = cut.panel_normal(panels[k]);
      const std::vector<Eigen::Vector3d>& polygon = polygons[k];
      for (int side : {1, -1}) {
        const Eigen::Vector3d outward = -side * n;  // the s > 0 material's outward normal points to s < 0
        for (std::size_t v = 1; v + 1 < polygon.size(); ++v)  // fan over the convex polygon
          buffer.add_triangle({polygon[0], polygon[v], polygon[v + 1]}, rule, t, side, outward);
      }
    }
  }
  return buffer.pack(true);
}

namespace {

/// MLS evaluations at the listed points (in increasing order), in parallel; a failure is the lowest point's.
std::vector<MlsEvaluation> evaluate_at(const MlsShapeFunctions& mls, const QuadraturePoints& points,
                                       const std::vector<int>& which, bool with_gradients) {
  std::vector<MlsEvaluation> evals(which.size());
  parallel_for(static_cast<int>(which.size()), 256, [&](int k) {
    const int q = which[k];
    mls.evaluate(points.points.row(q).transpose(), with_gradients, &evals[k], points.sides[q]);
  });
  return evals;
}

/// Empty slot arrays for `capacity` entries.
void allocate_slots(ShapeTable* t, long long capacity) {
  if (capacity > std::numeric_limits<int>::max())
    throw std::length_error(fmt::format("shape-function table: {} entries exceed the 32-bit slot index; use fewer "
                                        "nodes per support (support_factor) or a coarser cloud", capacity));
  const auto c = static_cast<std::size_t>(capacity);
  t->nodes.assign(c, 0);
  t->phi.assign(c, 0.0);
  t->dphi.setZero(3, t->gradients ? static_cast<Eigen::Index>(c) : 0);
  t->slots_used = 0;
}

/// Write an evaluation into the slots from `at` on.
void write_row(const MlsEvaluation& e, int at, ShapeTable* t) {
  for (int k = 0; k < e.size(); ++k) {
    t->nodes[at + k] = e.nodes[k];
    t->phi[at + k] = e.phi[k];
    if (t->gradients) t->dphi.col(at + k) = e.dphi.col(k);
  }
}

long long with_spare(long long entries, double spare_fraction) {
  return entries + static_cast<long long>(std::ceil(spare_fraction * static_cast<double>(entries)));
}

void take_points(QuadraturePoints points, ShapeTable* t) {
  t->points = std::move(points.points);
  t->weights = std::move(points.weights);
  t->cells = std::move(points.cells);
  t->sides = std::move(points.sides);
  t->normals = std::move(points.normals);
}

}  // namespace

long long ShapeTable::num_entries() const {
  long long total = 0;
  for (int q = 0; q < size(); ++q) total += row_end[q] - row_begin[q];
  return total;
}

ShapeTable tabulate_shape_functions(const MlsShapeFunctions& mls, QuadraturePoints points, bool with_gradients,
                                    double spare_fraction) {
  // An update of an empty table that evaluates every point: it packs them one after another, with the spare room.
  ShapeTable t;
  t.gradients = with_gradients;
  const std::vector<int> evaluate_all(points.size(), -1);
  update_shape_functions(mls, std::move(points), evaluate_all, spare_fraction, &t);
  return t;
}

TableUpdate update_shape_functions(const MlsShapeFunctions& mls, QuadraturePoints points, const std::vector<int>& reuse,
                                   double spare_fraction, ShapeTable* table) {
  const int nq = points.size();
  std::vector<int> evaluated;
  for (int q = 0; q < nq; ++q)
    if (reuse[q] < 0) evaluated.push_back(q);
  const std::vector<MlsEvaluation> evals = evaluate_at(mls, points, evaluated, table->gradients);
  TableUpdate report;
  report.rows_evaluated = static_cast<int>(evaluated.size());

  long long new_entries = 0, kept_entries = 0;
  for (const MlsEvaluation& e : evals) new_entries += e.size();
  for (int q = 0; q < nq; ++q)
    if (reuse[q] >= 0) kept_entries += table->end(reuse[q]) - table->begin(reuse[q]);
  std::vector<int> row_begin(nq), row_end(nq);
  const long long capacity = static_cast<long long>(table->nodes.size());
  if (table->slots_used + new_entries <= capacity) {
    // In place: the kept rows stay in their slots; the evaluated ones go into spare slots.
    for (int q = 0; q < nq; ++q)
      if (reuse[q] >= 0) {
        row_begin[q] = table->begin(reuse[q]);
        row_end[q] = table->end(reuse[q]);
      }
  } else {
    // Out of spare slots: pack the kept rows into new arrays with spare room again (a copy, as a full set-up's).
    ShapeTable packed;
    packed.gradients = table->gradients;
    allocate_slots(&packed, with_spare(kept_entries + new_entries, spare_fraction));
    int at = 0;
    for (int q = 0; q < nq; ++q)
      if (reuse[q] >= 0) {
        row_begin[q] = at;
        at += table->end(reuse[q]) - table->begin(reuse[q]);
        row_end[q] = at;
      }
#pragma omp parallel for schedule(static)
    for (int q = 0; q < nq; ++q) {
      if (reuse[q] < 0) continue;
      const int from = table->begin(reuse[q]), len = row_end[q] - row_begin[q];
      std::copy_n(table->nodes.begin() + from, len, packed.nodes.begin() + row_begin[q]);
      std::copy_n(table->phi.begin() + from, len, packed.phi.begin() + row_begin[q]);
      if (packed.gradients) packed.dphi.middleCols(row_begin[q], len) = table->dphi.middleCols(from, len);
    }
    packed.slots_used = at;
    table->nodes.swap(packed.nodes);
    table->phi.swap(packed.phi);
    table->dphi.swap(packed.dphi);
    table->slots_used = packed.slots_used;
    report.packed = true;
  }
  int at = table->slots_used;
  for (std::size_t k = 0; k < evaluated.size(); ++k) {
    row_begin[evaluated[k]] = at;
    at += evals[k].size();
    row_end[evaluated[k]] = at;
  }
#pragma omp parallel for schedule(static)
  for (int k = 0; k < report.rows_evaluated; ++k) write_row(evals[k], row_begin[evaluated[k]], table);
  table->slots_used = at;
  table->row_begin = std::move(row_begin);
  table->row_end = std::move(row_end);
  take_points(std::move(points), table);
  return report;
}

NodeIncidence::NodeIncidence(const ShapeTable& table, int num_nodes) : num_points(table.size()) {
  offsets.assign(num_nodes + 1, 0);
  for (int q = 0; q < table.size(); ++q)
    for (int s = table.begin(q); s < table.end(q); ++s) ++offsets[table.nodes[s] + 1];
  for (int i = 0; i < num_nodes; ++i) offsets[i + 1] += offsets[i];
  slots.resize(offsets.back());
  points.resize(offsets.back());
  std::vector<int> fill(offsets.begin(), offsets.end() - 1);
  for (int q = 0; q < table.size(); ++q)
    for (int s = table.begin(q); s < table.end(q); ++s) {
      const int at = fill[table.nodes[s]]++;
      slots[at] = s;
      points[at] = q;
    }
}

NodeIncidence::NodeIncidence(const NodeIncidence& before, const ShapeTable& table, const std::vector<int>& reuse) {
  merge_incidence(before, table, reuse, this);
}

void merge_incidence(const NodeIncidence& before, const ShapeTable& table, const std::vector<int>& reuse,
                     NodeIncidence* merged, const std::vector<int>* dropped_entries) {
  if (merged == &before) throw std::invalid_argument("merge_incidence: the result must not be the incidence before");
  NodeIncidence& out = *merged;
  std::vector<int>& offsets = out.offsets;
  std::vector<int>& slots = out.slots;
  std::vector<int>& points = out.points;
  const int num_nodes = static_cast<int>(before.offsets.size()) - 1;
  const int nq = table.size();
  const int old_points = before.num_points;
  out.num_points = nq;
  std::vector<int> new_of_old(old_points, -1), evaluated;
  int last = -1;
  for (int q = 0; q < nq; ++q) {
    if (reuse[q] < 0) {
      evaluated.push_back(q);
      continue;
    }
    if (reuse[q] <= last) {  // kept rows out of order: the merge below would not sort them
      out = NodeIncidence(table, num_nodes);
      return;
    }
    last = reuse[q];
    new_of_old.at(reuse[q]) = q;
  }

  // The evaluated rows' entries by node, in increasing point order.
  std::vector<int> added_offsets(num_nodes + 1, 0);
  for (int q : evaluated)
    for (int s = table.begin(q); s < table.end(q); ++s) ++added_offsets[table.nodes[s] + 1];
  for (int i = 0; i < num_nodes; ++i) added_offsets[i + 1] += added_offsets[i];
  std::vector<int> added_slots(added_offsets.back()), added_points(added_offsets.back());
  {
    std::vector<int> fill(added_offsets.begin(), added_offsets.end() - 1);
    for (int q : evaluated)
      for (int s = table.begin(q); s < table.end(q); ++s) {
        const int at = fill[table.nodes[s]]++;
        added_slots[at] = s;
        added_points[at] = q;
      }
  }

  // Node by node: the kept entries (still in increasing point order) merged with the added ones.
  offsets.assign(num_nodes + 1, 0);
  if (dropped_entries) {
    for (int i = 0; i < num_nodes; ++i)
      offsets[i + 1] = before.offsets[i + 1] - before.offsets[i] - (*dropped_entries)[i] + added_offsets[i + 1] -
                       added_offsets[i];
  } else {
#pragma omp parallel for schedule(static, 256)
    for (int i = 0; i < num_nodes; ++i) {
      int kept = 0;
      for (int e = before.offsets[i]; e < before.offsets[i + 1]; ++e) kept += new_of_old[before.points[e]] >= 0;
      offsets[i + 1] = kept + added_offsets[i + 1] - added_offsets[i];
    }
  }
  for (int i = 0; i < num_nodes; ++i) offsets[i + 1] += offsets[i];
  slots.resize(offsets.back());
  points.resize(offsets.back());
  int miscounted = 0;  // nodes whose given dropped count disagrees with the entries found (then transposed)
#pragma omp parallel for schedule(static, 256) reduction(+ : miscounted)
  for (int i = 0; i < num_nodes; ++i) {
    int at = offsets[i], a = added_offsets[i];
    for (int e = before.offsets[i]; e < before.offsets[i + 1]; ++e) {
      const int q = new_of_old[before.points[e]];
      if (q < 0) continue;
      for (; a < added_offsets[i + 1] && added_points[a] < q && at < offsets[i + 1]; ++a, ++at) {
        slots[at] = added_slots[a];
        points[at] = added_points[a];
      }
      if (at >= offsets[i + 1]) {  // more kept entries than counted: stop before writing past the node's range
        ++miscounted;
        break;
      }
      slots[at] = before.slots[e];
      points[at] = q;
      ++at;
    }
    for (; a < added_offsets[i + 1] && at < offsets[i + 1]; ++a, ++at) {
      slots[at] = added_slots[a];
      points[at] = added_points[a];
    }
    if (at != offsets[i + 1] || a != added_offsets[i + 1]) ++miscounted;
  }
  if (miscounted > 0) out = NodeIncidence(table, num_nodes);
}

}  // namespace meshless
