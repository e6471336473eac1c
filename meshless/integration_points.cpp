#include "meshless/integration_points.hpp"

#include <Eigen/Dense>
#include <exception>
#include <utility>

#include "meshless/gauss_quadrature_tet.hpp"
#include "meshless/mls_shape_functions.hpp"

namespace meshless {

void tet_quadrature_points(const core::TetMesh& mesh, int order, core::PointMatrix* points, Eigen::VectorXd* weights,
                           std::vector<int>* cells) {
  const SimplexRule rule = tet_rule(order);
  const int nt = mesh.num_tets(), nq = rule.size();
  points->resize(static_cast<Eigen::Index>(nt) * nq, 3);
  weights->resize(static_cast<Eigen::Index>(nt) * nq);
  cells->resize(static_cast<size_t>(nt) * nq);
  for (int t = 0; t < nt; ++t) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.tets(t, 0));
    Eigen::Matrix3d j;  // affine map X = a + J xi
    for (int c = 0; c < 3; ++c) j.col(c) = mesh.vertices.row(mesh.tets(t, c + 1)).transpose() - a;
    const double det = std::abs(j.determinant());
    for (int q = 0; q < nq; ++q) {
      const Eigen::Index row = static_cast<Eigen::Index>(t) * nq + q;
      points->row(row) = (a + j * rule.points[q]).transpose();
      (*weights)[row] = rule.weights[q] * det;
      (*cells)[row] = t;
    }
  }
}

void face_quadrature_points(const core::TetMesh& mesh, int order, core::PointMatrix* points, Eigen::VectorXd* weights,
                            std::vector<int>* faces) {
  const SimplexRule rule = triangle_rule(order);
  const int nf = static_cast<int>(mesh.boundary_faces.rows()), nq = rule.size();
  points->resize(static_cast<Eigen::Index>(nf) * nq, 3);
  weights->resize(static_cast<Eigen::Index>(nf) * nq);
  faces->resize(static_cast<size_t>(nf) * nq);
  for (int f = 0; f < nf; ++f) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.boundary_faces(f, 0));
    const Eigen::Vector3d e1 = mesh.vertices.row(mesh.boundary_faces(f, 1)).transpose() - a;
    const Eigen::Vector3d e2 = mesh.vertices.row(mesh.boundary_faces(f, 2)).transpose() - a;
    const double two_area = e1.cross(e2).norm();
    for (int q = 0; q < nq; ++q) {
      const Eigen::Index row = static_cast<Eigen::Index>(f) * nq + q;
      points->row(row) = (a + rule.points[q].x() * e1 + rule.points[q].y() * e2).transpose();
      (*weights)[row] = rule.weights[q] * two_area;
      (*faces)[row] = f;
    }
  }
}

ShapeTable tabulate_shape_functions(const MlsShapeFunctions& mls, core::PointMatrix points, Eigen::VectorXd weights,
                                    std::vector<int> cells, bool with_gradients) {
  const int nq = static_cast<int>(points.rows());
  std::vector<MlsEvaluation> evals(nq);
  // Exceptions must not escape an OpenMP region: keep the first one (lowest point index) and rethrow it.
  std::exception_ptr error;
  int error_point = nq;
#pragma omp parallel for schedule(dynamic, 256)
  for (int q = 0; q < nq; ++q) {
    try {
      mls.evaluate(points.row(q).transpose(), with_gradients, &evals[q]);
    } catch (...) {
#pragma omp critical(tabulate_error)
      if (q < error_point) {
        error_point = q;
        error = std::current_exception();
      }
    }
  }
  if (error) std::rethrow_exception(error);

  ShapeTable t;
  t.offsets.resize(nq + 1);
  t.offsets[0] = 0;
  for (int q = 0; q < nq; ++q) t.offsets[q + 1] = t.offsets[q] + evals[q].size();
  const int total = t.offsets[nq];
  t.nodes.resize(total);
  t.phi.resize(total);
  t.dphi.resize(3, with_gradients ? total : 0);
#pragma omp parallel for schedule(static)
  for (int q = 0; q < nq; ++q) {
    const MlsEvaluation& e = evals[q];
    for (int k = 0; k < e.size(); ++k) {
      t.nodes[t.offsets[q] + k] = e.nodes[k];
      t.phi[t.offsets[q] + k] = e.phi[k];
      if (with_gradients) t.dphi.col(t.offsets[q] + k) = e.dphi.col(k);
    }
  }
  t.points = std::move(points);
  t.weights = std::move(weights);
  t.cells = std::move(cells);
  return t;
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
