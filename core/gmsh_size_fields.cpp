#include "core/gmsh_size_fields.hpp"

#include <gmsh.h>

namespace core {

int add_curve_threshold_field(const std::vector<double>& curves, double fine, double size) {
  const int distance = gmsh::model::mesh::field::add("Distance");
  gmsh::model::mesh::field::setNumbers(distance, "CurvesList", curves);
  gmsh::model::mesh::field::setNumber(distance, "NumPointsPerCurve", 200);
  const int threshold = gmsh::model::mesh::field::add("Threshold");
  gmsh::model::mesh::field::setNumber(threshold, "InField", distance);
  gmsh::model::mesh::field::setNumber(threshold, "SizeMin", fine);
  gmsh::model::mesh::field::setNumber(threshold, "SizeMax", size);
  gmsh::model::mesh::field::setNumber(threshold, "DistMin", fine);
  gmsh::model::mesh::field::setNumber(threshold, "DistMax", fine + size);
  return threshold;
}

}  // namespace core
