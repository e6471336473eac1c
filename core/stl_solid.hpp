#pragma once
// An STL surface as an OpenCASCADE solid, so a body from CT segmentation takes the same boolean operations
// as the built-in lung: the region imprint (mesh-independent fixed and load regions) and the crack
// embedding of a cut (core/crack_embedding.hpp). Each STL triangle becomes one planar OCC face; faces share
// their edges and vertices, so the shell is closed without sewing and the geometry is the STL exactly.
#include "core/surface_query.hpp"

namespace core {

/// Add the closed, outward-oriented `surface` [m] to the current Gmsh model as an OCC volume in model
/// units of `to_m` metres (1e-3: mm, like the built-in lung). Returns the volume tag (model synchronised).
/// Throws std::runtime_error when OpenCASCADE cannot build the solid.
int add_stl_solid(const TriangleSurface& surface, double to_m);

}  // namespace core
