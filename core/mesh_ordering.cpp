#include "core/mesh_ordering.hpp"

#include <algorithm>
#include <array>
#include <boost/graph/adjacency_list.hpp>
#include <boost/graph/cuthill_mckee_ordering.hpp>
#include <numeric>
#include <utility>

namespace core {
namespace {

using Graph = boost::adjacency_list<boost::vecS, boost::vecS, boost::undirectedS>;

/// The vertex graph of the tetrahedra: one edge per distinct tet edge.
Graph vertex_graph(const TetMesh& mesh) {
  std::vector<std::pair<int, int>> edges;
  edges.reserve(6 * static_cast<std::size_t>(mesh.num_tets()));
  for (int t = 0; t < mesh.num_tets(); ++t)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) edges.emplace_back(std::minmax(mesh.tets(t, a), mesh.tets(t, b)));
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  return Graph(edges.begin(), edges.end(), static_cast<Graph::vertices_size_type>(mesh.num_vertices()));
}

/// The order of the rows of `m` (renumbered by `new_index`) by their sorted new vertex numbers.
template <class Rows>
std::vector<int> row_order(const Rows& m, const std::vector<int>& new_index) {
  constexpr int kCols = Rows::ColsAtCompileTime;
  std::vector<std::array<int, kCols>> keys(static_cast<std::size_t>(m.rows()));
  for (int r = 0; r < m.rows(); ++r) {
    for (int c = 0; c < kCols; ++c) keys[r][c] = new_index[m(r, c)];
    std::sort(keys[r].begin(), keys[r].end());
  }
  std::vector<int> order(keys.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return keys[a] < keys[b]; });
  return order;
}

/// Rows of `m` in `order`, their vertex ids renumbered (the column order, hence the orientation, is kept).
template <class Rows>
Rows reordered_rows(const Rows& m, const std::vector<int>& order, const std::vector<int>& new_index) {
  Rows out(m.rows(), m.cols());
  for (int r = 0; r < m.rows(); ++r)
    for (int c = 0; c < m.cols(); ++c) out(r, c) = new_index[m(order[r], c)];
  return out;
}

}  // namespace

std::vector<int> order_for_locality(TetMesh* mesh) {
  const int nv = mesh->num_vertices();
  const Graph graph = vertex_graph(*mesh);
  // Cuthill–McKee gives the old vertex of each new number; written backwards, that is the reverse order.
  std::vector<Graph::vertex_descriptor> old_of_new(static_cast<std::size_t>(nv));
  boost::cuthill_mckee_ordering(graph, old_of_new.rbegin());
  std::vector<int> new_index(static_cast<std::size_t>(nv));
  for (int k = 0; k < nv; ++k) new_index[old_of_new[k]] = k;

  PointMatrix vertices(nv, 3);
  std::vector<char> fixed(mesh->vertex_fixed.size());
  for (int k = 0; k < nv; ++k) {
    vertices.row(k) = mesh->vertices.row(static_cast<int>(old_of_new[k]));
    if (!fixed.empty()) fixed[k] = mesh->vertex_fixed[old_of_new[k]];
  }
  const std::vector<int> tet_order = row_order(mesh->tets, new_index);
  const std::vector<int> face_order = row_order(mesh->boundary_faces, new_index);
  std::vector<FaceTag> tags(mesh->face_tags.size());
  for (std::size_t f = 0; f < tags.size(); ++f) tags[f] = mesh->face_tags[face_order[f]];

  mesh->tets = reordered_rows(mesh->tets, tet_order, new_index);
  mesh->boundary_faces = reordered_rows(mesh->boundary_faces, face_order, new_index);
  mesh->vertices = std::move(vertices);
  mesh->vertex_fixed = std::move(fixed);
  mesh->face_tags = std::move(tags);
  return new_index;
}

}  // namespace core
