#include "meshless/efg_problem.hpp"

#include <fmt/format.h>

#include <stdexcept>

namespace meshless {

EfgProblem problem_from_case(const core::Case& c, const core::Geometry& g) {
  EfgProblem p;
  p.name = c.name;
  p.mesh = g.meshless_mesh;
  p.material = c.material;
  p.support.d_max = c.meshless.support_factor;
  p.support.k = c.meshless.support_neighbours;
  p.quadrature_order = c.meshless.quadrature_order;
  p.node_spacing = c.meshless.node_spacing;
  p.penalty_factor = c.meshless.penalty_factor;
  const double area = p.mesh.tagged_area(core::FaceTag::load);
  if (!(area > 0.0))
    throw std::runtime_error(fmt::format("case '{}': the meshless mesh has no load-tagged faces", c.name));
  const Eigen::Vector3d t = c.load.force / area;  // uniform traction: total force / A_patch
  p.traction = [t](const Eigen::Vector3d&) { return t; };
  const core::LoadSpec load = c.load;
  p.load_scale = [load](double time) { return load.force_scale(time); };
  for (int n = 1; n <= c.time.steps; ++n) p.step_times.push_back(n * c.time.dt());
  p.output_every = c.output.every;
  return p;
}

}  // namespace meshless
