#include "meshless/efg/penalty_boundary.hpp"

#include <Eigen/Dense>
#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

namespace meshless {

BoundaryTerms make_boundary_terms(const EfgProblem& problem, const ShapeTable& surface, double alpha) {
  const core::TetMesh& mesh = problem.mesh;
  const int nf = static_cast<int>(mesh.boundary_faces.rows());
  const int n = mesh.num_vertices();
  auto role = [&](const std::vector<char>& mask, core::FaceTag tag, int f) {
    if (!mask.empty()) return mask[f] != 0;
    return f < static_cast<int>(mesh.face_tags.size()) && mesh.face_tags[f] == tag;
  };
  if (!problem.penalised_faces.empty() && static_cast<int>(problem.penalised_faces.size()) != nf)
    throw std::invalid_argument(fmt::format("EfgProblem: penalised_faces has {} entries for {} faces",
                                            problem.penalised_faces.size(), nf));
  if (!problem.loaded_faces.empty() && static_cast<int>(problem.loaded_faces.size()) != nf)
    throw std::invalid_argument(
        fmt::format("EfgProblem: loaded_faces has {} entries for {} faces", problem.loaded_faces.size(), nf));

  BoundaryTerms b;
  b.penalty_weight.assign(surface.size(), 0.0);
  b.traction_weight.assign(surface.size(), 0.0);
  b.penalty_load = Eigen::VectorXd::Zero(3 * n);
  b.traction_load = Eigen::VectorXd::Zero(3 * n);
  for (int q = 0; q < surface.size(); ++q) {
    const double w = surface.weights[q];
    const Eigen::Vector3d x = surface.points.row(q).transpose();
    if (surface.on_lip(q)) {  // a lip of the cut: free, unless a verification problem loads it
      if (problem.lip_traction) {
        const Eigen::Vector3d t = problem.lip_traction(x, surface.normals.col(q));
        for (int s = surface.begin(q); s < surface.end(q); ++s)
          b.traction_load.segment<3>(3 * surface.nodes[s]) += w * surface.phi[s] * t;
      }
      continue;
    }
    const int f = surface.cells[q];
    if (role(problem.penalised_faces, core::FaceTag::fixed, f)) {
      // eq. 23; an elastic support's alpha is its k_s(x), which makes the term its Robin condition exactly.
      const double alpha_q = problem.support_stiffness ? problem.support_stiffness(x) : alpha;
      b.penalty_weight[q] = alpha_q * w;
      b.largest_alpha = std::max(b.largest_alpha, alpha_q);
      b.penalised_area += w;
      if (problem.prescribed_displacement) {
        const Eigen::Vector3d ubar = problem.prescribed_displacement(x);
        for (int s = surface.begin(q); s < surface.end(q); ++s)
          b.penalty_load.segment<3>(3 * surface.nodes[s]) += alpha_q * w * surface.phi[s] * ubar;
      }
    }
    if (role(problem.loaded_faces, core::FaceTag::load, f)) {
      b.traction_weight[q] = w;
      b.loaded_area += w;
      if (problem.traction) {
        const Eigen::Vector3d t = problem.traction(x);  // eq. 24, traction term
        for (int s = surface.begin(q); s < surface.end(q); ++s)
          b.traction_load.segment<3>(3 * surface.nodes[s]) += w * surface.phi[s] * t;
      }
    }
  }
  if (!b.penalty_load.allFinite() || !b.traction_load.allFinite())
    throw std::runtime_error("EfgModel: non-finite prescribed displacement or traction on the boundary");
  return b;
}

}  // namespace meshless
