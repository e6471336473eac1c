// libFuzzer target: the project's STL path on arbitrary bytes. The bytes are written to an .stl file and read
// as a case's geometry (core::build_reference_surface): Gmsh reads the file, then core checks that the
// triangles form a closed 2-manifold and orients them outward. Every input must give a closed, outward
// surface or a core::CaseError at /geometry/stl_file; any other exception, a crash or a sanitizer report is
// a finding.
#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/case.hpp"
#include "core/geometry.hpp"

namespace {

const std::string& input_file() {
  static const std::string file =
      (std::filesystem::temp_directory_path() / ("tissue_fuzz_stl_" + std::to_string(getpid()) + ".stl"))
          .string();
  return file;
}

[[noreturn]] void finding(const std::string& what) {
  std::fprintf(stderr, "%s\n", what.c_str());
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  {
    std::ofstream out(input_file(), std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    if (!out) finding("cannot write " + input_file());
  }
  core::Case c;
  c.name = "fuzz";
  c.source_file = "fuzz/case.json";
  c.geometry.source = core::GeometrySpec::Source::stl;
  c.geometry.stl_file = input_file();
  c.geometry.stl_unit_to_m = 1e-3;
  try {
    double volume = 0.0;
    const core::TriangleSurface s = core::build_reference_surface(c, &volume);
    // Accepted: closed, every triangle index valid, oriented outward (non-negative enclosed volume).
    if (s.count_non_manifold_edges() != 0) finding("accepted a surface with open edges");
    if (s.triangles.size() > 0 &&
        (s.triangles.minCoeff() < 0 || s.triangles.maxCoeff() >= static_cast<int>(s.vertices.rows())))
      finding("accepted a surface with a bad vertex index");
    if (std::isfinite(volume) && volume < 0.0) finding("accepted an inward-oriented surface");
  } catch (const core::CaseError& e) {
    if (std::string(e.what()).find("/geometry/stl_file") == std::string::npos)
      finding(std::string("CaseError not at /geometry/stl_file: ") + e.what());
  } catch (const std::exception& e) {
    finding(std::string("the STL reader threw something other than CaseError: ") + e.what());
  }
  return 0;
}
