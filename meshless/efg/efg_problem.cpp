#include "meshless/efg/efg_problem.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "core/load_program.hpp"

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
  if (c.fixed_region.support == core::FixedRegionSpec::Support::elastic) {
    const core::FixedRegionSpec region = c.fixed_region;
    p.support_stiffness = [region](const Eigen::Vector3d& x) { return region.support_stiffness(x); };
  }
  const core::LoadProgram program = core::load_program(c, p.mesh);
  const Eigen::Vector3d t = program.traction;
  p.traction = [t](const Eigen::Vector3d&) { return t; };
  p.load_scale = [program](double time) { return program.scale(time); };
  p.step_times = program.step_times;
  p.min_step = program.min_step;
  p.output_every = c.output.every;
  p.cut = g.cut;
  p.cut_treatment = cut_treatment_from_name(c.meshless.enrichment);
  p.front_transition = c.meshless.front_transition;
  p.variationally_consistent = c.meshless.variationally_consistent;
  return p;
}

}  // namespace meshless
