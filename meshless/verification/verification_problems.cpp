#include "meshless/verification/verification_problems.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <random>

#include "core/kelvin_law.hpp"
#include "core/timoshenko_cantilever.hpp"
#include "meshless/verification/box_mesh.hpp"
#include "meshless/verification/linear_patch_field.hpp"
#include "meshless/efg/efg_model.hpp"
#include "meshless/mls/mls_shape_functions.hpp"
#include "meshless/mls/node_search.hpp"
#include "meshless/mls/support_radii.hpp"

namespace meshless {

namespace {

core::KelvinParameters tissue_material(double nu) {
  core::KelvinParameters m;
  m.K1 = 6000.0;
  m.K2 = 12000.0;
  m.eta = 18000.0;
  m.nu = nu;
  m.k = 0.0;
  return m;
}

EfgProblem box_problem(const std::string& name, core::TetMesh mesh, double spacing, int order, double nu) {
  EfgProblem p;
  p.name = name;
  p.mesh = std::move(mesh);
  p.material = tissue_material(nu);
  p.support.d_max = 2.0;
  p.support.k = 6;
  p.quadrature_order = order;
  p.node_spacing = spacing;
  p.penalty_factor = 1e3;
  p.step_times = {0.0};  // one instantaneous step: E_k = C(K1, nu), the elastic limit
  return p;
}

}  // namespace

InvariantReport mls_invariants(int points, unsigned seed) {
  const double a = 0.01;
  const core::TetMesh mesh = make_box_mesh(Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(0.1), 10, 10, 10, {},
                                           0.2, seed);
  NodeSearch search(mesh.vertices);
  SupportRadiiParams params;
  params.d_max = 2.0;
  params.k = 6;
  SupportRadii radii(mesh.vertices, search, params);
  MlsShapeFunctions mls(mesh.vertices, radii, search);
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(0.0, 0.1);
  InvariantReport r;
  r.num_nodes = mesh.num_vertices();
  r.num_points = points;
  for (int p = 0; p < points; ++p) {
    const Eigen::Vector3d x(u(gen), u(gen), u(gen));
    const MlsEvaluation e = mls.evaluate(x, true);
    r.record(mesh.vertices, x, e.nodes, e.phi, e.dphi, a);
  }
  return r;
}

PatchTestReport run_patch_test(int quadrature_order, bool variationally_consistent, int cells) {
  const double edge = 0.05, spacing = edge / cells;
  core::TetMesh mesh = make_box_mesh(Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(edge), cells, cells, cells,
                                     {}, 0.2, 11);
  EfgProblem p = box_problem("patch test", std::move(mesh), spacing, quadrature_order, 0.3);
  const int nf = static_cast<int>(p.mesh.boundary_faces.rows());
  p.penalised_faces.assign(nf, 1);  // penalty u-bar on ALL faces
  p.loaded_faces.assign(nf, 1);
  const LinearPatchField field;
  const Eigen::Vector3d a0 = field.a0;
  const Eigen::Matrix3d g = field.G;
  const core::Vector6 eps_exact = field.strain();
  const core::Matrix3 sigma = field.stress(core::KelvinLaw(p.material));
  p.prescribed_displacement = [field](const Eigen::Vector3d& x) { return field.displacement(x); };
  // The exact field also carries the traction sigma n on the boundary: without it the (inconsistent) penalty
  // method would be off by O(sigma / alpha) however accurate the integration.
  // The face normal of a box face is one of +-e_d: recover it from the point (faces are on the box planes).
  p.traction = [sigma, edge](const Eigen::Vector3d& x) -> Eigen::Vector3d {
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    double best = 1e30;
    for (int d = 0; d < 3; ++d) {
      if (std::abs(x[d]) < best) { best = std::abs(x[d]); n = -Eigen::Vector3d::Unit(d); }
      if (std::abs(x[d] - edge) < best) { best = std::abs(x[d] - edge); n = Eigen::Vector3d::Unit(d); }
    }
    return sigma * n;
  };
  p.variationally_consistent = variationally_consistent;
  EfgModel model(std::move(p));
  model.run();

  PatchTestReport r;
  r.quadrature_order = quadrature_order;
  r.variationally_consistent = variationally_consistent;
  r.num_nodes = model.statistics().num_nodes;
  r.newton_iterations = model.steps().back().newton_iterations;
  std::mt19937 gen(5);
  std::uniform_real_distribution<double> u(0.05 * edge, 0.95 * edge);
  core::PointMatrix pts(500, 3);
  for (int i = 0; i < pts.rows(); ++i) pts.row(i) << u(gen), u(gen), u(gen);
  const core::PointMatrix uh = model.displacements_at(pts);
  double max_err = 0.0, max_u = 0.0;
  for (int i = 0; i < pts.rows(); ++i) {
    const Eigen::Vector3d exact = a0 + g * pts.row(i).transpose();
    max_err = std::max(max_err, (uh.row(i).transpose() - exact).norm());
    max_u = std::max(max_u, exact.norm());
  }
  r.max_relative_error = max_err / max_u;
  for (const core::Vector6& e : model.quadrature_strains())
    r.strain_relative_error = std::max(r.strain_relative_error, (e - eps_exact).norm() / eps_exact.norm());
  return r;
}

CantileverReport run_cantilever(int nd, int quadrature_order, bool variationally_consistent, double d_max) {
  const double L = 0.1, D = 0.02, T = 0.02, P = 1e-3;
  const double h = D / nd;
  auto tagger = [L](const Eigen::Vector3d& c, const Eigen::Vector3d&) {
    if (c.x() < 1e-12) return core::FaceTag::fixed;
    if (c.x() > L - 1e-12) return core::FaceTag::load;
    return core::FaceTag::free_surface;
  };
  core::TetMesh mesh = make_box_mesh(Eigen::Vector3d(0.0, -D / 2, -T / 2), Eigen::Vector3d(L, D / 2, T / 2), 5 * nd,
                                     nd, nd, tagger);
  EfgProblem p = box_problem("cantilever", std::move(mesh), h, quadrature_order, 0.0);
  p.support.d_max = d_max;
  const double E = p.material.K1;
  // Clamped at x = 0 to the exact displacement, shear P at x = L (exact 3-D elasticity for nu = 0).
  const core::TimoshenkoCantilever exact{P, E, p.material.nu, L, D, T * D * D * D / 12.0};
  auto exact_u = [exact](const Eigen::Vector3d& x) { return exact.displacement(x); };
  auto exact_strain = [exact](const Eigen::Vector3d& x) { return exact.strain(x); };
  p.prescribed_displacement = exact_u;
  p.traction = [exact](const Eigen::Vector3d& x) { return exact.end_traction(x); };
  p.variationally_consistent = variationally_consistent;
  EfgModel model(std::move(p));
  model.run();

  CantileverReport r;
  r.cells_through_height = nd;
  r.node_spacing = h;
  r.num_nodes = model.statistics().num_nodes;
  const ShapeTable& vt = model.volume_points();
  const std::vector<core::Vector6> strains = model.quadrature_strains();
  const core::KelvinLaw law(model.problem().material);
  const core::Matrix6 C = law.elastic_matrix(E);
  const Eigen::VectorXd& U = model.nodal_parameters();
  double e2 = 0, u2 = 0, en2 = 0, ee2 = 0;
  for (int q = 0; q < vt.size(); ++q) {
    const Eigen::Vector3d x = vt.points.row(q).transpose();
    Eigen::Vector3d uh = Eigen::Vector3d::Zero();
    for (int s = vt.begin(q); s < vt.end(q); ++s) uh += vt.phi[s] * U.segment<3>(3 * vt.nodes[s]);
    const Eigen::Vector3d ue = exact_u(x);
    const core::Vector6 de = strains[q] - exact_strain(x), ex = exact_strain(x);
    e2 += vt.weights[q] * (uh - ue).squaredNorm();
    u2 += vt.weights[q] * ue.squaredNorm();
    en2 += vt.weights[q] * de.dot(C * de);
    ee2 += vt.weights[q] * ex.dot(C * ex);
  }
  r.l2_error = std::sqrt(e2 / u2);
  r.energy_error = std::sqrt(en2 / ee2);
  r.tip_deflection = model.displacement_at(Eigen::Vector3d(L, 0.0, 0.0)).y();
  r.exact_tip_deflection = exact_u(Eigen::Vector3d(L, 0.0, 0.0)).y();
  r.seconds = model.timings().setup_seconds + model.timings().shape_function_seconds +
              model.timings().assembly_seconds + model.timings().solve_seconds;
  return r;
}

CreepReport run_creep_bar(int steps, double support_stiffness) {
  const double L = 0.04, a = 0.01, sigma0 = 100.0, t_end = 4.0;
  auto tagger = [L](const Eigen::Vector3d& c, const Eigen::Vector3d&) {
    if (c.x() < 1e-12) return core::FaceTag::fixed;
    if (c.x() > L - 1e-12) return core::FaceTag::load;
    return core::FaceTag::free_surface;  // lateral faces free
  };
  core::TetMesh mesh = make_box_mesh(Eigen::Vector3d::Zero(), Eigen::Vector3d(L, a, a), 8, 2, 2, tagger);
  EfgProblem p = box_problem("creep bar", std::move(mesh), a / 2, 2, 0.0);
  p.traction = [sigma0](const Eigen::Vector3d&) { return Eigen::Vector3d(sigma0, 0.0, 0.0); };
  if (support_stiffness > 0.0)
    p.support_stiffness = [support_stiffness](const Eigen::Vector3d&) { return support_stiffness; };
  p.step_times = {0.0};  // step load at t = 0: instantaneous response first
  for (int n = 1; n <= steps; ++n) p.step_times.push_back(t_end * n / steps);
  CreepReport r;
  const core::KelvinParameters m = p.material;
  EfgModel model(std::move(p));
  model.run([&](const EfgModel& mdl, const StepRecord& rec) {
    const double u0 = mdl.displacement_at(Eigen::Vector3d(0.0, a / 2, a / 2)).x();
    const double eps = (mdl.displacement_at(Eigen::Vector3d(L, a / 2, a / 2)).x() - u0) / L;
    const double exact = sigma0 / m.K1 + sigma0 / m.K2 * (1.0 - std::exp(-m.K2 * rec.time / m.eta));
    r.times.push_back(rec.time);
    r.strain.push_back(eps);
    r.exact.push_back(exact);
    r.max_relative_error = std::max(r.max_relative_error, std::abs(eps - exact) / exact);
    if (support_stiffness > 0.0) {
      const double exact_u0 = sigma0 / support_stiffness;
      r.max_support_relative_error = std::max(r.max_support_relative_error, std::abs(u0 - exact_u0) / exact_u0);
    }
  });
  r.num_nodes = model.statistics().num_nodes;
  return r;
}

EfgProblem sheared_box_problem(int points_per_side, double spacing) {
  const int cells = points_per_side - 1;
  const double edge = cells * spacing;
  auto tagger = [edge](const Eigen::Vector3d& c, const Eigen::Vector3d&) {
    if (c.z() < 1e-12) return core::FaceTag::fixed;
    if (c.z() > edge - 1e-12) return core::FaceTag::load;
    return core::FaceTag::free_surface;
  };
  EfgProblem p;
  p.name = "sheared box";
  p.mesh = make_box_mesh(Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(edge), cells, cells, cells, tagger, 0.2, 3);
  p.material = {6000.0, 12000.0, 18000.0, 0.4, 0.0};
  p.support.d_max = 2.0;
  p.support.k = 6;
  p.quadrature_order = 2;
  p.node_spacing = spacing;
  p.penalty_factor = 1e3;
  p.traction = [](const Eigen::Vector3d&) { return Eigen::Vector3d(10.0, 0.0, 0.0); };
  p.step_times = {0.0};
  return p;
}

}  // namespace meshless
