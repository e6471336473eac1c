#pragma once
// VTU output for ParaView through deal.II's DataOutBase writer (no hand-written XML).
// Fields are either per point (one row per vertex) or per cell (one row per tet/triangle); a field
// with 3 columns is written as a vector.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/tet_mesh.hpp"

namespace experiments {

struct VtuField {
  std::string name;
  Eigen::MatrixXd values;  ///< #items by 1 (scalar) or #items by 3 (vector)
};

void write_tet_vtu(const std::string& path, const core::PointMatrix& vertices, const core::TetMatrix& tets,
                   const std::vector<VtuField>& point_fields, const std::vector<VtuField>& cell_fields);

void write_triangle_vtu(const std::string& path, const core::PointMatrix& vertices,
                        const core::TriMatrix& triangles, const std::vector<VtuField>& point_fields,
                        const std::vector<VtuField>& cell_fields);

void write_point_vtu(const std::string& path, const core::PointMatrix& points,
                     const std::vector<VtuField>& point_fields);

}  // namespace experiments
