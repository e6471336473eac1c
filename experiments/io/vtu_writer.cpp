#include "experiments/io/vtu_writer.hpp"

#include <deal.II/base/data_out_base.h>
#include <deal.II/grid/reference_cell.h>

#include <fstream>
#include <stdexcept>
#include <tuple>

namespace experiments {
namespace {

using namespace dealii;

using Ranges = std::vector<
    std::tuple<unsigned int, unsigned int, std::string, DataComponentInterpretation::DataComponentInterpretation>>;

/// Data-set names and vector ranges for deal.II, in field order (point fields then cell fields).
void describe(const std::vector<VtuField>& point_fields, const std::vector<VtuField>& cell_fields,
              std::vector<std::string>* names, Ranges* ranges) {
  for (const auto* fields : {&point_fields, &cell_fields})
    for (const auto& f : *fields) {
      if (f.values.cols() == 3) {
        ranges->emplace_back(names->size(), names->size() + 2, f.name,
                             DataComponentInterpretation::component_is_part_of_vector);
        for (int c = 0; c < 3; ++c) names->push_back(f.name);
      } else if (f.values.cols() == 1) {
        names->push_back(f.name);
      } else {
        throw std::invalid_argument("VTU field '" + f.name + "' must have 1 or 3 columns");
      }
    }
}

/// One patch per cell; vertices are duplicated per patch, so per-cell data is simply constant on it.
template <int dim, int n_vertices, typename CellMatrix>
void write_cells(const std::string& path, const core::PointMatrix& vertices, const CellMatrix& cells,
                 ReferenceCell reference_cell, const std::vector<VtuField>& point_fields,
                 const std::vector<VtuField>& cell_fields) {
  for (const auto& f : point_fields)
    if (f.values.rows() != vertices.rows()) throw std::invalid_argument("VTU point field '" + f.name + "' size");
  for (const auto& f : cell_fields)
    if (f.values.rows() != cells.rows()) throw std::invalid_argument("VTU cell field '" + f.name + "' size");
  std::vector<std::string> names;
  Ranges ranges;
  describe(point_fields, cell_fields, &names, &ranges);

  std::vector<DataOutBase::Patch<dim, 3>> patches(static_cast<std::size_t>(cells.rows()));
  for (Eigen::Index c = 0; c < cells.rows(); ++c) {
    auto& patch = patches[static_cast<std::size_t>(c)];
    if constexpr (dim > 0) {  // Patch<0,3> fixes these as constants (a single vertex)
      patch.reference_cell = reference_cell;
      patch.n_subdivisions = 1;
    }
    patch.patch_index = static_cast<unsigned int>(c);
    patch.points_are_available = false;
    patch.data.reinit(names.size(), n_vertices);
    for (int v = 0; v < n_vertices; ++v) {
      const int id = cells(c, v);
      patch.vertices[v] = Point<3>(vertices(id, 0), vertices(id, 1), vertices(id, 2));
      unsigned int row = 0;
      for (const auto& f : point_fields)
        for (int k = 0; k < f.values.cols(); ++k) patch.data(row++, v) = f.values(id, k);
      for (const auto& f : cell_fields)
        for (int k = 0; k < f.values.cols(); ++k) patch.data(row++, v) = f.values(c, k);
    }
  }
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  DataOutBase::VtkFlags flags;
  DataOutBase::write_vtu(patches, names, ranges, flags, out);
  if (!out) throw std::runtime_error("error while writing " + path);
}

}  // namespace

void write_tet_vtu(const std::string& path, const core::PointMatrix& vertices, const core::TetMatrix& tets,
                   const std::vector<VtuField>& point_fields, const std::vector<VtuField>& cell_fields) {
  write_cells<3, 4>(path, vertices, tets, ReferenceCells::Tetrahedron, point_fields, cell_fields);
}

void write_triangle_vtu(const std::string& path, const core::PointMatrix& vertices,
                        const core::TriMatrix& triangles, const std::vector<VtuField>& point_fields,
                        const std::vector<VtuField>& cell_fields) {
  write_cells<2, 3>(path, vertices, triangles, ReferenceCells::Triangle, point_fields, cell_fields);
}

void write_point_vtu(const std::string& path, const core::PointMatrix& points,
                     const std::vector<VtuField>& point_fields) {
  Eigen::Matrix<int, Eigen::Dynamic, 1> ids(points.rows());
  for (Eigen::Index i = 0; i < points.rows(); ++i) ids(i) = static_cast<int>(i);
  write_cells<0, 1>(path, points, ids, ReferenceCells::Vertex, point_fields, {});
}

}  // namespace experiments
