#include "core/load_program.hpp"

#include <fmt/format.h>

namespace core {

LoadProgram load_program(const Case& c, const TetMesh& mesh) {
  LoadProgram p;
  p.patch_area = mesh.tagged_area(FaceTag::load);
  if (!(p.patch_area > 0.0))
    throw CaseError(c.source_file, "/load/radius",
                    fmt::format("the load patch holds no boundary face of the mesh; expected a radius larger than the "
                                "mesh size ({:.3g} mm)",
                                c.load.radius * 1e3));
  p.traction = c.load.force / p.patch_area;  // uniform traction: total force / patch area
  p.load = c.load;
  for (int n = 1; n <= c.time.steps; ++n) p.step_times.push_back(n * c.time.dt());
  p.min_step = c.time.minimum_step();
  return p;
}

}  // namespace core
