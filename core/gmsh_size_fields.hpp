#pragma once
// Gmsh size fields that refine a mesh along singular lines, shared by the case's geometry pipeline
// (core/geometry.cpp, refine_regions) and the cracked block of the crack tests (core/crack_embedding.hpp), so that a
// model problem is graded exactly as the lung is. Model units throughout (the callers mesh in mm); call with a Gmsh
// model current (core::GmshSession).
#include <vector>

namespace core {

/// Adds a Distance + Threshold field: size `fine` within `fine` of the curves, growing linearly to `size` at
/// distance `fine + size`. Returns the field's tag, to be combined (Min) or set as the background mesh.
int add_curve_threshold_field(const std::vector<double>& curves, double fine, double size);

}  // namespace core
