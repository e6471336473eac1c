#include "meshless/lrpim/lrpim_case.hpp"

#include <chrono>
#include <fstream>
#include <string>

#include "core/case_error.hpp"
#include "core/load_program.hpp"
#include "meshless/lrpim/lrpim_model.hpp"
#include "meshless/mls/node_search.hpp"

namespace meshless::lrpim {

namespace {

// Peak resident memory of this process so far [bytes] (VmHWM of /proc/self/status); 0 where unavailable.
double peak_resident_bytes() {
  std::ifstream status("/proc/self/status");
  std::string key;
  while (status >> key) {
    if (key == "VmHWM:") {
      double kb = 0.0;
      status >> kb;
      return kb * 1024.0;
    }
    status.ignore(1 << 12, '\n');
  }
  return 0.0;
}

/// The rows of `nodes` that keep at least `separation` [m] from every row kept before them.
core::PointMatrix separated_nodes(const core::PointMatrix& nodes, double separation) {
  if (!(separation > 0.0)) return nodes;
  const meshless::NodeSearch search(nodes);
  std::vector<char> kept(nodes.rows(), 0);
  std::vector<meshless::NodeHit> hits;
  Eigen::Index count = 0;
  for (Eigen::Index i = 0; i < nodes.rows(); ++i) {
    search.within_radius(nodes.row(i).transpose(), separation, &hits);
    bool keep = true;
    for (const meshless::NodeHit& h : hits) keep = keep && !(h.node < i && kept[h.node]);
    kept[i] = keep;
    count += keep;
  }
  core::PointMatrix out(count, 3);
  for (Eigen::Index i = 0, k = 0; i < nodes.rows(); ++i)
    if (kept[i]) out.row(k++) = nodes.row(i);
  return out;
}

}  // namespace

LrpimProblem lrpim_problem_from_case(const core::Case& c, const core::Geometry& g, const LrpimCaseOptions& options) {
  if (c.cut || g.cut)
    throw core::CaseError(c.source_file, "/cut",
                          "the LRPIM model has no crack treatment; remove /cut from the case, or drop lrpim from the "
                          "models it runs");
  LrpimProblem p;
  p.name = c.name;
  p.nodes = separated_nodes(g.meshless_mesh.vertices, options.min_node_separation * c.meshless.node_spacing);
  p.body = SurfaceBody::from_mesh_boundary(g.meshless_mesh);
  const bool elastic = c.fixed_region.support == core::FixedRegionSpec::Support::elastic;
  // Indexed by core::FaceTag: free, fixed, load, crack (a cut case is refused above).
  p.conditions = {FaceCondition::free_surface,
                  elastic ? FaceCondition::elastic_support : FaceCondition::displacement, FaceCondition::traction,
                  FaceCondition::free_surface};
  if (elastic) {
    const core::FixedRegionSpec region = c.fixed_region;
    p.support_stiffness = [region](const Eigen::Vector3d& x) { return region.support_stiffness(x); };
  } else {
    p.prescribed_displacement = [](const Eigen::Vector3d&) { return Eigen::Vector3d::Zero(); };
  }
  LrpimLoad load = lrpim_load_from_case(c, g);
  p.traction = std::move(load.traction);
  p.load_scale = std::move(load.load_scale);
  p.step_times = std::move(load.step_times);
  p.material = c.material;
  p.node_spacing = c.meshless.node_spacing;
  p.rpim = options.rpim;
  p.alpha_q = options.alpha_q;
  p.local_spacing = options.local_spacing;
  p.rule = options.rule;
  p.newton_tolerance = options.newton_tolerance;
  p.max_newton_iterations = options.max_newton_iterations;
  p.refactor_contraction = options.refactor_contraction;
  p.linear_solver = options.linear_solver;
  p.krylov_options = options.krylov_options;
  p.divergence_correction = options.divergence_correction;
  p.test_function = options.test_function;
  p.balance_rigid_modes = options.balance_rigid_modes;
  return p;
}

LrpimLoad lrpim_load_from_case(const core::Case& c, const core::Geometry& g) {
  const core::LoadProgram program = core::load_program(c, g.meshless_mesh);
  const Eigen::Vector3d t = program.traction;
  return LrpimLoad{[t](const Eigen::Vector3d&) { return t; }, [program](double time) { return program.scale(time); },
                   program.step_times};
}

LrpimCaseRun run_lrpim_case(const core::Case& c, const core::Geometry& g, const LrpimCaseOptions& options) {
  LrpimModel model(lrpim_problem_from_case(c, g, options));
  return run_lrpim_model(model, c, g, options.on_step);
}

LrpimCaseRun run_lrpim_model(LrpimModel& model, const core::Case& c, const core::Geometry& g,
                             const std::function<void(const LrpimStepReport&)>& on_step) {
  const core::LoadProgram program = core::load_program(c, g.meshless_mesh);
  const double load_area = model.problem().body->labelled_area(static_cast<int>(core::FaceTag::load));
  LrpimCaseRun run;
  const LrpimStatistics& st = model.statistics();
  run.setup_seconds = st.setup_seconds;
  run.n_nodes = st.num_nodes;
  run.n_dofs = 3 * st.num_nodes;
  model.run([&](const LrpimModel&, const LrpimStepRecord& rec) {
    LrpimStepReport s;
    s.step = static_cast<int>(run.steps.size()) + 1;
    s.time = rec.time;
    s.wall_seconds = rec.wall_seconds;
    s.assembly_seconds = rec.assembly_seconds;
    s.solve_seconds = rec.solve_seconds;
    s.newton_iterations = rec.newton_iterations;
    s.factorisations = rec.factorisations;
    s.residuals = rec.residuals;
    s.rejected_mixes = rec.rejected_mixes;
    run.steps.push_back(s);
    if (on_step) on_step(s);
  });
  run.sample_displacements.resize(g.sample_points.rows(), 3);
  for (Eigen::Index i = 0; i < g.sample_points.rows(); ++i)
    run.sample_displacements.row(i) = model.displacement_at(g.sample_points.row(i).transpose()).transpose();

  const LrpimProblem& p = model.problem();
  nlohmann::json& d = run.details;
  d["model"] = "LRPIM (RPIM: MQ + linear basis; MLPG1 local weak form; docs/LRPIM.md)";
  d["nodes"] = st.num_nodes;
  d["dofs"] = 3 * st.num_nodes;
  d["constrained_nodes"] = st.num_constrained_nodes;
  d["boundary_triangles"] = p.body->num_triangles();
  d["points"] = {{"volume", st.num_volume_points},
                 {"reaction", st.num_reaction_points},
                 {"elastic_support", st.num_support_points},
                 {"traction", st.num_traction_points}};
  d["tangent_entries"] = st.matrix_entries;
  d["min_rcond"] = st.min_rcond;
  d["divergence_defect"] = st.divergence_defect;
  d["parameters"] = {{"alpha_q", p.alpha_q},
                     {"r_q_m", p.alpha_q * p.node_spacing},
                     {"node_spacing_m", p.node_spacing},
                     {"rpim", {{"num_neighbours", p.rpim.num_neighbours}, {"q", p.rpim.q}, {"alpha_c", p.rpim.alpha_c}}},
                     {"rule",
                      {{"polar", p.rule.polar},
                       {"azimuthal", p.rule.azimuthal},
                       {"radial", p.rule.radial},
                       {"boundary_order", p.rule.boundary_order},
                       {"boundary_subdivision", p.rule.boundary_subdivision}}},
                     {"divergence_correction", p.divergence_correction},
                     {"test_function", p.test_function == LrpimTestFunction::mls       ? "mls"
                                       : p.test_function == LrpimTestFunction::shepard ? "shepard"
                                                                                        : "spline"},
                     {"balance_rigid_modes", p.balance_rigid_modes},
                     {"newton_tolerance", p.newton_tolerance},
                     {"refactor_contraction", p.refactor_contraction},
                     {"linear_solver", p.linear_solver == LrpimLinearSolver::mumps ? "MUMPS sparse LU (METIS)"
                                       : p.linear_solver == LrpimLinearSolver::petsc_krylov
                                           ? "PETSc " + p.krylov_options
                                           : "Eigen SparseLU (COLAMD)"}};
  d["support"] = c.fixed_region.support == core::FixedRegionSpec::Support::elastic ? "elastic (Robin term)"
                                                                                     : "clamp (nodal u = 0)";
  d["load"] = {{"patch_area_m2", program.patch_area},
               {"body_load_area_m2", load_area},
               {"traction_pa", {program.traction.x(), program.traction.y(), program.traction.z()}},
               {"total_force_n",
                {program.traction.x() * load_area, program.traction.y() * load_area, program.traction.z() * load_area}}};
  {
    const LrpimGlobalBalance b = model.global_balance();
    auto mn = [](const Eigen::Vector3d& v) { return std::vector<double>{1e3 * v.x(), 1e3 * v.y(), 1e3 * v.z()}; };
    d["global_balance_mn"] = {{"applied_force", mn(b.applied_force)},
                              {"support_force", mn(b.support_force)},
                              {"applied_moment_mn_m", mn(b.applied_moment)},
                              {"support_moment_mn_m", mn(b.support_moment)},
                              {"test_weighted_applied", mn(b.test_weighted_applied)},
                              {"test_weighted_support", mn(b.test_weighted_support)}};
    const LrpimBalanceCorrection bc = model.balance_correction();
    d["balance_correction_mn"] = {{"active", bc.active},
                                  {"net_force", mn(bc.net_force)},
                                  {"net_moment_mn_m", mn(bc.net_moment)}};
  }
  d["seconds"] = {{"setup", st.setup_seconds}, {"assembly", st.assembly_seconds}, {"solve", st.solve_seconds}};
  d["factorisations"] = st.factorisations;
  d["krylov_iterations"] = st.krylov_iterations;
  d["peak_resident_bytes"] = peak_resident_bytes();
  return run;
}

}  // namespace meshless::lrpim
