#pragma once
// A look at an STL file's layout before Gmsh reads it. Gmsh trusts a binary STL's header: it allocates
// 50 bytes per announced triangle (a 32-bit count, so up to 4 GB) before it reads them, so a truncated or
// corrupt file can exhaust the memory. Found by fuzzing the STL path (tests/fuzz/fuzz_stl_reader.cpp).
#include <string>

namespace core {

/// Empty when `file` looks like an ASCII STL ("solid" first, with at least one "vertex") or is a binary STL of
/// exactly 84 + 50 N bytes for the N triangles its header announces; otherwise what is wrong, phrased as what
/// was expected (the caller turns it into a CaseError at /geometry/stl_file). An ASCII file whose facets Gmsh
/// cannot parse still reaches Gmsh's binary fallback, which reserves (but does not touch) up to 4 GB of address
/// space and then reports no facets.
std::string check_stl_layout(const std::string& file);

}  // namespace core
