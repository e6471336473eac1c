#include "tests/surrogate_box_case.hpp"

#include <algorithm>

#include "meshless/verification/box_mesh.hpp"

namespace meshless {
namespace {
constexpr double kMm = 1e-3;
}  // namespace

EfgProblem surrogate_box_problem() {
  EfgProblem p;
  p.name = "surrogate box";
  p.mesh = make_box_mesh({0, 0, 0}, {40 * kMm, 40 * kMm, 20 * kMm}, 8, 8, 4,
                         [](const Eigen::Vector3d& c, const Eigen::Vector3d&) {
                           return c.z() < 1e-9 ? core::FaceTag::fixed : core::FaceTag::free_surface;
                         });
  p.material = {6000.0, 12000.0, 18000.0, 0.4, 1.0};
  p.support.d_max = 2.0;
  p.support.k = 6;
  p.quadrature_order = 2;
  p.node_spacing = 5 * kMm;
  p.penalty_factor = 1e3;
  p.load_scale = [](double t) { return std::min(t / 1.0, 1.0); };
  p.step_times = {0.5, 1.0};
  return p;
}

core::SurrogateSpec surrogate_box_spec() {
  core::SurrogateSpec s;
  s.contact_points = {{20 * kMm, 20 * kMm, 20 * kMm}};
  s.patch_radius = 6 * kMm;
  s.contact_length = 2 * s.patch_radius;  // the case reader's default
  s.max_force = 0.05;
  s.force_levels = 4;
  s.holdout_forces = 2;
  return s;
}

}  // namespace meshless
