#include "reference_fem/triangulation_from_mesh.hpp"

#include <deal.II/grid/tria_description.h>

#include <algorithm>
#include <array>
#include <map>
#include <stdexcept>

namespace reference_fem {

void build_triangulation(const core::TetMesh& mesh, dealii::Triangulation<3>* triangulation) {
  std::vector<dealii::Point<3>> vertices(static_cast<std::size_t>(mesh.num_vertices()));
  for (int v = 0; v < mesh.num_vertices(); ++v)
    vertices[v] = dealii::Point<3>(mesh.vertices(v, 0), mesh.vertices(v, 1), mesh.vertices(v, 2));
  std::vector<dealii::CellData<3>> cells;
  cells.reserve(static_cast<std::size_t>(mesh.num_tets()));
  for (int t = 0; t < mesh.num_tets(); ++t) {
    dealii::CellData<3> cell(4);  // a tetrahedron: deal.II's reference tet has the same orientation
    for (unsigned int k = 0; k < 4; ++k) cell.vertices[k] = static_cast<unsigned int>(mesh.tets(t, k));
    cell.material_id = 0;
    cells.push_back(cell);
  }
  triangulation->create_triangulation(vertices, cells, dealii::SubCellData());

  // Boundary ids by vertex triple: deal.II keeps the vertex numbering, so the tags match exactly.
  std::map<std::array<unsigned int, 3>, unsigned int> tag_of_face;
  for (int f = 0; f < mesh.boundary_faces.rows(); ++f) {
    std::array<unsigned int, 3> key{};
    for (int k = 0; k < 3; ++k) key[k] = static_cast<unsigned int>(mesh.boundary_faces(f, k));
    std::sort(key.begin(), key.end());
    tag_of_face[key] = static_cast<unsigned int>(mesh.face_tags[f]);
  }
  for (const auto& cell : triangulation->active_cell_iterators())
    for (const auto f : cell->face_indices()) {
      if (!cell->face(f)->at_boundary()) continue;
      std::array<unsigned int, 3> key{};
      for (unsigned int k = 0; k < 3; ++k) key[k] = cell->face(f)->vertex_index(k);
      std::sort(key.begin(), key.end());
      const auto it = tag_of_face.find(key);
      if (it == tag_of_face.end())
        throw std::runtime_error("build_triangulation: a boundary face of the tet mesh has no tag");
      cell->face(f)->set_boundary_id(static_cast<dealii::types::boundary_id>(it->second));
    }
}

}  // namespace reference_fem
