#include "meshless/integration_points.hpp"

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <exception>
#include <utility>

#include "meshless/cut_quadrature.hpp"
#include "meshless/gauss_quadrature_tet.hpp"
#include "meshless/mls_shape_functions.hpp"

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

ShapeTable tabulate(const MlsShapeFunctions& mls, QuadraturePoints points, bool with_gradients,
                    const ShapeTable* previous, const std::vector<int>* reuse) {
  const int nq = points.size();
  std::vector<MlsEvaluation> evals(nq);
  // Exceptions must not escape an OpenMP region: keep the first one (lowest point index) and rethrow it.
  std::exception_ptr error;
  int error_point = nq;
#pragma omp parallel for schedule(dynamic, 256)
  for (int q = 0; q < nq; ++q) {
    if (reuse && (*reuse)[q] >= 0) continue;
    try {
      mls.evaluate(points.points.row(q).transpose(), with_gradients, &evals[q], points.sides[q]);
    } catch (...) {
#pragma omp critical(tabulate_error)
      if (q < error_point) {
        error_point = q;
        error = std::current_exception();
      }
    }
  }
  if (error) std::rethrow_exception(error);

  auto row_size = [&](int q) {
    if (reuse && (*reuse)[q] >= 0) return previous->end((*reuse)[q]) - previous->begin((*reuse)[q]);
    return evals[q].size();
  };
  ShapeTable t;
  t.offsets.resize(nq + 1);
  t.offsets[0] = 0;
  for (int q = 0; q < nq; ++q) t.offsets[q + 1] = t.offsets[q] + row_size(q);
  const int total = t.offsets[nq];
  t.nodes.resize(total);
  t.phi.resize(total);
  t.dphi.resize(3, with_gradients ? total : 0);
#pragma omp parallel for schedule(static)
  for (int q = 0; q < nq; ++q) {
    if (reuse && (*reuse)[q] >= 0) {  // whole rows: most of a local update's table is copied
      const int from = previous->begin((*reuse)[q]), to = t.offsets[q], len = row_size(q);
      std::copy_n(previous->nodes.begin() + from, len, t.nodes.begin() + to);
      std::copy_n(previous->phi.begin() + from, len, t.phi.begin() + to);
      if (with_gradients) t.dphi.middleCols(to, len) = previous->dphi.middleCols(from, len);
      continue;
    }
    const MlsEvaluation& e = evals[q];
    for (int k = 0; k < e.size(); ++k) {
      t.nodes[t.offsets[q] + k] = e.nodes[k];
      t.phi[t.offsets[q] + k] = e.phi[k];
      if (with_gradients) t.dphi.col(t.offsets[q] + k) = e.dphi.col(k);
    }
  }
  t.points = std::move(points.points);
  t.weights = std::move(points.weights);
  t.cells = std::move(points.cells);
  t.sides = std::move(points.sides);
  t.normals = std::move(points.normals);
  return t;
}

}  // namespace

ShapeTable tabulate_shape_functions(const MlsShapeFunctions& mls, QuadraturePoints points, bool with_gradients) {
  return tabulate(mls, std::move(points), with_gradients, nullptr, nullptr);
}

ShapeTable tabulate_shape_functions(const MlsShapeFunctions& mls, QuadraturePoints points, bool with_gradients,
                                    const ShapeTable& previous, const std::vector<int>& reuse) {
  return tabulate(mls, std::move(points), with_gradients, &previous, &reuse);
}

NodeIncidence::NodeIncidence(const ShapeTable& table, int num_nodes) {
  offsets.assign(num_nodes + 1, 0);
  for (int node : table.nodes) ++offsets[node + 1];
  for (int i = 0; i < num_nodes; ++i) offsets[i + 1] += offsets[i];
  slots.resize(table.nodes.size());
  points.resize(table.nodes.size());
  std::vector<int> fill(offsets.begin(), offsets.end() - 1);
  for (int q = 0; q < table.size(); ++q)
    for (int s = table.begin(q); s < table.end(q); ++s) {
      const int at = fill[table.nodes[s]]++;
      slots[at] = s;
      points[at] = q;
    }
}

}  // namespace meshless
