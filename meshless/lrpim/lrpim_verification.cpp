#include "meshless/lrpim/lrpim_verification.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <chrono>
#include <random>
#include <string>

#include "core/convergence_rate.hpp"
#include "core/kelvin_law.hpp"
#include "core/timoshenko_cantilever.hpp"
#include "meshless/lrpim/local_quadrature.hpp"
#include "meshless/lrpim/lrpim_model.hpp"
#include "meshless/mls/node_search.hpp"
#include "meshless/verification/box_mesh.hpp"
#include "meshless/verification/linear_patch_field.hpp"

namespace meshless::lrpim {

namespace {

core::KelvinParameters tissue_material(double nu, double k) {
  core::KelvinParameters m;
  m.K1 = 6000.0;
  m.K2 = 12000.0;
  m.eta = 18000.0;
  m.nu = nu;
  m.k = k;
  return m;
}

core::PointMatrix box_nodes(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int nx, int ny, int nz,
                            double jitter, unsigned seed) {
  return make_box_mesh(lo, hi, nx, ny, nz, {}, jitter, seed).vertices;
}

}  // namespace

RpimInvariantReport rpim_invariants(const RpimParameters& parameters, int points, unsigned seed) {
  const double a = 0.01;
  const core::PointMatrix nodes = box_nodes(Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(0.1), 10, 10, 10, 0.2, seed);
  NodeSearch search(nodes);
  RpimShapeFunctions rpim(nodes, search, a, parameters);
  RpimInvariantReport r;
  r.num_nodes = static_cast<int>(nodes.rows());
  r.num_points = points;
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(0.0, 0.1);
  RpimEvaluation e;
  for (int p = 0; p < points; ++p) {
    const Eigen::Vector3d x(u(gen), u(gen), u(gen));
    rpim.evaluate(x, true, &e);
    r.min_rcond = std::min(r.min_rcond, e.rcond);
    r.min_spread = std::min(r.min_spread, e.spread);
    r.record(nodes, x, e.nodes, e.phi, e.dphi, a);
  }
  for (int j = 0; j < nodes.rows(); ++j) {
    rpim.evaluate(nodes.row(j).transpose(), false, &e);
    for (int k = 0; k < e.size(); ++k)
      r.max_kronecker_error = std::max(r.max_kronecker_error, std::abs(e.phi[k] - (e.nodes[k] == j ? 1.0 : 0.0)));
  }
  return r;
}

LrpimPatchReport run_lrpim_patch_test(int cells, double alpha_q, int polar, int azimuthal, bool divergence_correction,
                                      bool cloud_surface) {
  const double edge = 0.05, spacing = edge / cells;
  LrpimProblem p;
  p.name = "lrpim patch test";
  const core::TetMesh mesh =
      make_box_mesh(Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(edge), cells, cells, cells, {}, 0.2, 11);
  p.nodes = mesh.vertices;
  if (cloud_surface) {
    // Label each boundary triangle with its box face (-x +x -y +y -z +z) from its outward normal.
    const SurfaceBody faces = SurfaceBody::from_mesh_boundary(mesh);
    std::vector<int> labels(faces.num_triangles());
    for (int t = 0; t < faces.num_triangles(); ++t) {
      const Eigen::Vector3d& n = faces.normal(t);
      int axis = 0;
      n.cwiseAbs().maxCoeff(&axis);
      labels[t] = 2 * axis + (n[axis] > 0.0 ? 1 : 0);
    }
    p.body = SurfaceBody(faces.vertices(), faces.triangles(), labels);
  } else {
    p.body = SurfaceBody::from_box(BoxBody{Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(edge)});
  }
  p.conditions = {FaceCondition::displacement, FaceCondition::traction, FaceCondition::displacement,
                  FaceCondition::traction,     FaceCondition::displacement, FaceCondition::traction};
  p.material = tissue_material(0.3, 0.0);
  p.node_spacing = spacing;
  p.alpha_q = alpha_q;
  p.rule.polar = polar;
  p.rule.azimuthal = azimuthal;
  p.divergence_correction = divergence_correction;
  const LinearPatchField field;
  const Eigen::Vector3d a0 = field.a0;
  const Eigen::Matrix3d g = field.G;
  const core::Vector6 eps_exact = field.strain();
  const core::Matrix3 sigma = field.stress(core::KelvinLaw(p.material));
  p.prescribed_displacement = [field](const Eigen::Vector3d& x) { return field.displacement(x); };
  // Traction faces are the +x, +y, +z planes: n = e_d of the coordinate that sits on edge.
  p.traction = [sigma, edge](const Eigen::Vector3d& x) -> Eigen::Vector3d {
    int d = 0;
    for (int k = 1; k < 3; ++k)
      if (std::abs(x[k] - edge) < std::abs(x[d] - edge)) d = k;
    return sigma * Eigen::Vector3d::Unit(d);
  };
  LrpimModel model(std::move(p));
  model.run();
  LrpimPatchReport r;
  r.cells = cells;
  r.num_nodes = model.statistics().num_nodes;
  r.newton_iterations = model.steps().back().newton_iterations;
  r.divergence_defect = model.statistics().divergence_defect;
  std::mt19937 gen(5);
  std::uniform_real_distribution<double> u(0.05 * edge, 0.95 * edge);
  double max_err = 0.0, max_u = 0.0;
  for (int i = 0; i < 500; ++i) {
    const Eigen::Vector3d x(u(gen), u(gen), u(gen));
    const Eigen::Vector3d exact = a0 + g * x;
    max_err = std::max(max_err, (model.displacement_at(x) - exact).norm());
    max_u = std::max(max_u, exact.norm());
    r.strain_relative_error =
        std::max(r.strain_relative_error, (model.strain_at(x) - eps_exact).norm() / eps_exact.norm());
  }
  r.max_relative_error = max_err / max_u;
  double nodal = 0.0;
  const core::PointMatrix& nodes = model.problem().nodes;
  for (int i = 0; i < nodes.rows(); ++i) {
    const Eigen::Vector3d x = nodes.row(i).transpose();
    nodal = std::max(nodal, (model.nodal_displacements().segment<3>(3 * i) - (a0 + g * x)).norm());
  }
  r.nodal_relative_error = nodal / max_u;
  return r;
}

namespace {
constexpr double kCantileverLength = 0.1, kCantileverDepth = 0.02, kCantileverThickness = 0.02, kCantileverShear = 1e-3;

// Clamped at x = 0 to the exact displacement, shear P at x = L (exact 3-D elasticity for nu = 0).
core::TimoshenkoCantilever cantilever_solution(const core::KelvinParameters& m) {
  const double D = kCantileverDepth, T = kCantileverThickness;
  return core::TimoshenkoCantilever{kCantileverShear, m.K1, m.nu, kCantileverLength, D, T * D * D * D / 12.0};
}
}  // namespace

LrpimProblem lrpim_cantilever_problem(int nd, const RpimParameters& rpim, double alpha_q) {
  const double L = kCantileverLength, D = kCantileverDepth, T = kCantileverThickness;
  const double h = D / nd;
  LrpimProblem p;
  p.name = "lrpim cantilever";
  const BoxBody box{Eigen::Vector3d(0.0, -D / 2, -T / 2), Eigen::Vector3d(L, D / 2, T / 2)};
  p.body = SurfaceBody::from_box(box);
  p.nodes = box_nodes(box.lo, box.hi, 5 * nd, nd, nd, 0.0, 1);
  p.conditions = {FaceCondition::displacement, FaceCondition::traction};
  p.material = tissue_material(0.0, 0.0);
  p.node_spacing = h;
  p.rpim = rpim;
  p.alpha_q = alpha_q;
  const core::TimoshenkoCantilever exact = cantilever_solution(p.material);
  p.prescribed_displacement = [exact](const Eigen::Vector3d& x) { return exact.displacement(x); };
  p.traction = [exact](const Eigen::Vector3d& x) { return exact.end_traction(x); };
  return p;
}

LrpimCantileverReport run_lrpim_cantilever(int nd, const RpimParameters& rpim, double alpha_q,
                                           const std::function<void(LrpimProblem*)>& adjust) {
  const double L = kCantileverLength, D = kCantileverDepth, T = kCantileverThickness;
  const double h = D / nd;
  LrpimProblem p = lrpim_cantilever_problem(nd, rpim, alpha_q);
  if (adjust) adjust(&p);
  const core::TimoshenkoCantilever exact = cantilever_solution(p.material);
  auto exact_u = [exact](const Eigen::Vector3d& x) { return exact.displacement(x); };
  auto exact_strain = [exact](const Eigen::Vector3d& x) { return exact.strain(x); };
  const core::KelvinLaw law(p.material);
  const core::Matrix6 C = law.elastic_matrix(p.material.K1);
  LrpimModel model(std::move(p));
  model.run();
  LrpimCantileverReport r;
  r.cells_through_height = nd;
  r.node_spacing = h;
  r.num_nodes = model.statistics().num_nodes;
  // Error norms on a 3-point Gauss grid over 5 nd x nd x nd cells: independent of the model's local quadrature.
  std::vector<double> gx, gw;
  gauss_legendre(3, &gx, &gw);
  const int n[3] = {5 * nd, nd, nd};
  const Eigen::Vector3d lo(0.0, -D / 2, -T / 2), size(L, D, T);
  double e2 = 0, u2 = 0, en2 = 0, ee2 = 0;
  for (int i = 0; i < n[0]; ++i)
    for (int j = 0; j < n[1]; ++j)
      for (int k = 0; k < n[2]; ++k)
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b)
            for (int c = 0; c < 3; ++c) {
              const Eigen::Vector3d cell(size[0] / n[0], size[1] / n[1], size[2] / n[2]);
              const Eigen::Vector3d x = lo + Eigen::Vector3d((i + 0.5 + 0.5 * gx[a]) * cell[0],
                                                             (j + 0.5 + 0.5 * gx[b]) * cell[1],
                                                             (k + 0.5 + 0.5 * gx[c]) * cell[2]);
              const double w = gw[a] * gw[b] * gw[c] * cell.prod() / 8.0;
              const Eigen::Vector3d ue = exact_u(x);
              const core::Vector6 ex = exact_strain(x), de = model.strain_at(x) - ex;
              e2 += w * (model.displacement_at(x) - ue).squaredNorm();
              u2 += w * ue.squaredNorm();
              en2 += w * de.dot(C * de);
              ee2 += w * ex.dot(C * ex);
            }
  r.l2_error = std::sqrt(e2 / u2);
  r.energy_error = std::sqrt(en2 / ee2);
  r.tip_deflection = model.displacement_at(Eigen::Vector3d(L, 0.0, 0.0)).y();
  r.exact_tip_deflection = exact_u(Eigen::Vector3d(L, 0.0, 0.0)).y();
  r.seconds = model.statistics().setup_seconds + model.statistics().assembly_seconds + model.statistics().solve_seconds;
  return r;
}

LrpimCreepReport run_lrpim_creep_bar(double k, int steps) {
  const double L = 0.04, a = 0.01, sigma0 = 100.0, t_end = 4.0;
  LrpimProblem p;
  p.name = "lrpim creep bar";
  const BoxBody box{Eigen::Vector3d::Zero(), Eigen::Vector3d(L, a, a)};
  p.body = SurfaceBody::from_box(box);
  p.nodes = box_nodes(box.lo, box.hi, 8, 2, 2, 0.0, 1);
  p.conditions = {FaceCondition::displacement, FaceCondition::traction};
  p.material = tissue_material(0.0, k);
  p.node_spacing = a / 2;
  p.prescribed_displacement = [](const Eigen::Vector3d&) { return Eigen::Vector3d::Zero(); };
  p.traction = [sigma0](const Eigen::Vector3d&) { return Eigen::Vector3d(sigma0, 0.0, 0.0); };
  p.step_times = {0.0};  // step load at t = 0: instantaneous response first
  for (int n = 1; n <= steps; ++n) p.step_times.push_back(t_end * n / steps);
  const core::KelvinParameters m = p.material;
  LrpimCreepReport r;
  r.k = k;
  LrpimModel model(std::move(p));
  model.run([&](const LrpimModel& mdl, const LrpimStepRecord& rec) {
    const double u0 = mdl.displacement_at(Eigen::Vector3d(0.0, a / 2, a / 2)).x();
    const double eps = (mdl.displacement_at(Eigen::Vector3d(L, a / 2, a / 2)).x() - u0) / L;
    const double n_exact = sigma0 / m.K1 + sigma0 / m.K2 * (1.0 - std::exp(-m.K2 * rec.time / m.eta));
    const double exact = k == 0.0 ? n_exact : (std::sqrt(1.0 + 4.0 * k * n_exact) - 1.0) / (2.0 * k);
    r.times.push_back(rec.time);
    r.strain.push_back(eps);
    r.exact.push_back(exact);
    r.max_relative_error = std::max(r.max_relative_error, std::abs(eps - exact) / exact);
  });
  r.num_nodes = model.statistics().num_nodes;
  return r;
}

}  // namespace meshless::lrpim

namespace meshless::lrpim {

nlohmann::json run_lrpim_verification(bool quick) {
  using nlohmann::json;
  const auto t0 = std::chrono::steady_clock::now();
  json out;
  out["quick"] = quick;
  bool all = true;
  auto item = [&](const std::string& name, json figures, bool passed) {
    figures["passed"] = passed;
    all = all && passed;
    out[name] = std::move(figures);
  };

  const RpimInvariantReport inv = rpim_invariants({}, quick ? 500 : 2000);
  item("rpim_invariants",
       {{"nodes", inv.num_nodes},
        {"points", inv.num_points},
        {"partition", inv.max_partition_error},
        {"linear_reproduction", inv.max_reproduction_error},
        {"gradient_sum", inv.max_gradient_sum},
        {"gradient_reproduction", inv.max_gradient_reproduction},
        {"kronecker_delta", inv.max_kronecker_error},
        {"min_rcond", inv.min_rcond},
        {"min_spread", inv.min_spread},
        {"bounds", {{"partition", 1e-13}, {"linear_reproduction", 1e-12}, {"gradient_sum", 1e-13},
                    {"gradient_reproduction", 1e-12}, {"kronecker_delta", 1e-11}, {"min_rcond", 1e-10}}}},
       inv.max_partition_error < 1e-13 && inv.max_reproduction_error < 1e-12 && inv.max_gradient_sum < 1e-13 &&
           inv.max_gradient_reproduction < 1e-12 && inv.max_kronecker_error < 1e-11 && inv.min_rcond > 1e-10);

  const int cells = quick ? 4 : 5;
  auto patch_json = [](const LrpimPatchReport& r) {
    return json{{"nodes", r.num_nodes},       {"cells", r.cells},
                {"displacement", r.max_relative_error}, {"nodal", r.nodal_relative_error},
                {"strain", r.strain_relative_error},   {"newton_iterations", r.newton_iterations},
                {"divergence_defect", r.divergence_defect}};
  };
  auto round_off = [](const LrpimPatchReport& r) {
    return r.max_relative_error < 1e-13 && r.nodal_relative_error < 1e-13 && r.strain_relative_error < 1e-11 &&
           r.newton_iterations == 1;
  };
  const LrpimPatchReport box = run_lrpim_patch_test(cells, 1.5, 8, 16, true, false);
  json j = patch_json(box);
  j["bounds"] = {{"displacement", 1e-13}, {"nodal", 1e-13}, {"strain", 1e-11}, {"newton_iterations", 1}};
  item("patch_test_box", j, round_off(box));
  const LrpimPatchReport cloud = run_lrpim_patch_test(cells, 1.5, 8, 16, true, true);
  j = patch_json(cloud);
  j["bounds"] = {{"displacement", 1e-13}, {"nodal", 1e-13}, {"strain", 1e-11}, {"newton_iterations", 1}};
  item("patch_test_cloud_surface", j, round_off(cloud));
  // Without the correction: what the angular rule leaves (5.2e-4 at 5 cells with the Shepard test functions, 1.9e-3
  // with the plain spline); reported, not a pass condition.
  out["patch_test_uncorrected"] = patch_json(run_lrpim_patch_test(cells, 1.5, 8, 16, false, false));

  std::vector<double> h, l2, en;
  json levels = json::array();
  for (int nd : quick ? std::vector<int>{2, 3} : std::vector<int>{2, 3, 4}) {
    const LrpimCantileverReport r = run_lrpim_cantilever(nd);
    h.push_back(r.node_spacing);
    l2.push_back(r.l2_error);
    en.push_back(r.energy_error);
    levels.push_back({{"cells_through_height", nd},
                      {"nodes", r.num_nodes},
                      {"l2", r.l2_error},
                      {"energy", r.energy_error},
                      {"tip_over_exact", r.tip_deflection / r.exact_tip_deflection},
                      {"seconds", r.seconds}});
  }
  const double rate_l2 = core::convergence_rate(h, l2), rate_en = core::convergence_rate(h, en);
  item("cantilever",
       {{"levels", levels},
        {"rate_l2", rate_l2},
        {"rate_energy", rate_en},
        {"bounds", {{"rate_l2", 2.0}, {"rate_energy", 1.1}}},  // 2.39 and 1.20 over 2-4 cells (5.0, 1.23 over 2-3)
        {"efg_rates_for_comparison", {{"l2", 1.96}, {"energy", 1.42}}}},
       rate_l2 > 2.0 && rate_en > 1.1);

  // The creep bar's error is the recursion's time-step error: 2.6e-5 at 40 steps of 0.1 s, 4.2e-4 at 10 steps of 0.4 s.
  const int steps = quick ? 10 : 40;
  const double creep_bound = quick ? 5e-4 : 3e-5;
  for (double k : {0.0, 2.0}) {
    const LrpimCreepReport r = run_lrpim_creep_bar(k, steps);
    item(k == 0.0 ? "creep_bar_k0" : "creep_bar_k2",
         {{"k", k}, {"steps", steps}, {"nodes", r.num_nodes}, {"max_relative_error", r.max_relative_error},
          {"bound", creep_bound}},
         r.max_relative_error < creep_bound);
  }
  out["passed"] = all;
  out["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace meshless::lrpim
