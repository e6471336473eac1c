#include "core/gmsh_mesh.hpp"

#include <gmsh.h>

#include <algorithm>
#include <array>
#include <unordered_map>
#include <vector>

namespace core {
namespace {

/// The current Gmsh mesh's elements of one type as (vertices in metres, connectivity). Nodes are numbered
/// densely in order of first use, so only the nodes those elements reference are kept.
template <int N>
void read_elements(int element_type, double to_m, PointMatrix* vertices,
                   Eigen::Matrix<int, Eigen::Dynamic, N, Eigen::RowMajor>* cells) {
  std::vector<std::size_t> elem_tags, node_tags;
  gmsh::model::mesh::getElementsByType(element_type, elem_tags, node_tags);
  std::vector<std::size_t> all_tags;
  std::vector<double> coords, param;
  gmsh::model::mesh::getNodes(all_tags, coords, param, -1, -1, true, false);
  std::unordered_map<std::size_t, std::size_t> tag_to_coord;
  for (std::size_t i = 0; i < all_tags.size(); ++i) tag_to_coord[all_tags[i]] = i;
  std::unordered_map<std::size_t, int> index;
  std::vector<Eigen::Vector3d> pts;
  cells->resize(static_cast<Eigen::Index>(node_tags.size() / N), N);
  for (std::size_t k = 0; k < node_tags.size(); ++k) {
    auto [it, inserted] = index.emplace(node_tags[k], static_cast<int>(pts.size()));
    if (inserted) {
      const std::size_t c = tag_to_coord.at(node_tags[k]);
      pts.emplace_back(coords[3 * c] * to_m, coords[3 * c + 1] * to_m, coords[3 * c + 2] * to_m);
    }
    (*cells)(static_cast<Eigen::Index>(k / N), static_cast<Eigen::Index>(k % N)) = it->second;
  }
  vertices->resize(static_cast<Eigen::Index>(pts.size()), 3);
  for (std::size_t i = 0; i < pts.size(); ++i) vertices->row(static_cast<Eigen::Index>(i)) = pts[i];
}

}  // namespace

TriangleSurface read_gmsh_triangles(double to_m) {
  TriangleSurface s;
  read_elements<3>(2, to_m, &s.vertices, &s.triangles);
  return s;
}

TetMesh read_gmsh_tets(double to_m) {
  TetMesh mesh;
  read_elements<4>(4, to_m, &mesh.vertices, &mesh.tets);
  finish_topology(&mesh);
  return mesh;
}

void finish_topology(TetMesh* mesh) {
  for (int t = 0; t < mesh->num_tets(); ++t) {
    const auto v = mesh->tets.row(t);
    if (tet_volume(mesh->vertices.row(v(0)), mesh->vertices.row(v(1)), mesh->vertices.row(v(2)),
                   mesh->vertices.row(v(3))) < 0)
      std::swap(mesh->tets(t, 2), mesh->tets(t, 3));
  }
  // Faces opposite vertex 0..3 of a positive tet, ordered so the normal points away from that vertex.
  static const int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  struct Entry {
    std::array<int, 3> key;
    std::array<int, 3> oriented;
  };
  std::vector<Entry> faces;
  faces.reserve(4 * mesh->num_tets());
  for (int t = 0; t < mesh->num_tets(); ++t)
    for (const auto& f : kFace) {
      Entry e;
      e.oriented = {mesh->tets(t, f[0]), mesh->tets(t, f[1]), mesh->tets(t, f[2])};
      e.key = e.oriented;
      std::sort(e.key.begin(), e.key.end());
      faces.push_back(e);
    }
  std::sort(faces.begin(), faces.end(), [](const Entry& a, const Entry& b) { return a.key < b.key; });
  std::vector<std::array<int, 3>> boundary;
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i;
    while (j < faces.size() && faces[j].key == faces[i].key) ++j;
    if (j - i == 1) boundary.push_back(faces[i].oriented);
    i = j;
  }
  mesh->boundary_faces.resize(static_cast<Eigen::Index>(boundary.size()), 3);
  for (std::size_t f = 0; f < boundary.size(); ++f)
    for (int k = 0; k < 3; ++k) mesh->boundary_faces(static_cast<Eigen::Index>(f), k) = boundary[f][k];
  mesh->face_tags.assign(boundary.size(), FaceTag::free_surface);
  mesh->vertex_fixed.assign(mesh->num_vertices(), 0);
}

}  // namespace core
