#include "experiments/models/efg/meshless_runs.hpp"

#include <fmt/format.h>

#include <chrono>
#include <optional>
#include <iostream>

#include "core/convergence_rate.hpp"
#include "core/output_directory.hpp"
#include "core/case.hpp"
#include "core/inadmissible_strain.hpp"
#include "experiments/studies/crack_opening.hpp"
#include "experiments/models/model_result.hpp"
#include "experiments/io/progress.hpp"
#include "experiments/io/vtu_writer.hpp"
#include "meshless/cut/cut_quadrature.hpp"
#include "meshless/efg/efg_model.hpp"
#include "meshless/mls/mls_shape_functions.hpp"
#include "meshless/verification/verification_problems.hpp"

namespace experiments {

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

Eigen::MatrixXd vector_field(const core::PointMatrix& m) { return Eigen::MatrixXd(m); }

/// Both lips of the model's cut inside the body as triangles, each vertex with the displacement of its own lip, so
/// the cut shows open when warped by the displacement (ParaView: Warp By Vector).
void write_lips_vtu(const std::string& path, const meshless::EfgModel& model) {
  const core::RuledSurface& cut = *model.problem().cut;
  const core::TetMesh& mesh = model.problem().mesh;
  std::vector<Eigen::Vector3d> vertices;
  std::vector<int> lip_of_vertex;
  std::vector<std::vector<Eigen::Vector3d>> polygons;
  for (int t = 0; t < mesh.num_tets(); ++t) {
    meshless::TetVertices tet;
    for (int k = 0; k < 4; ++k) tet[k] = mesh.vertices.row(mesh.tets(t, k)).transpose();
    meshless::panels_crossing_tet(cut, tet, &polygons);
    for (const auto& polygon : polygons)
      for (int side : {1, -1})
        for (std::size_t v = 1; v + 1 < polygon.size(); ++v)
          for (const Eigen::Vector3d& x : {polygon[0], polygon[v], polygon[v + 1]}) {
            vertices.push_back(x);
            lip_of_vertex.push_back(side);
          }
  }
  const Eigen::Index n = static_cast<Eigen::Index>(vertices.size());
  core::PointMatrix points(n, 3);
  core::TriMatrix triangles(n / 3, 3);
  Eigen::MatrixXd displacement(n, 3), lip(n / 3, 1);
  for (Eigen::Index v = 0; v < n; ++v) {
    points.row(v) = vertices[v].transpose();
    displacement.row(v) = model.displacement_at(vertices[v], lip_of_vertex[v]).transpose();
    if (v % 3 == 0) {
      triangles.row(v / 3) << static_cast<int>(v), static_cast<int>(v + 1), static_cast<int>(v + 2);
      lip(v / 3, 0) = lip_of_vertex[v];
    }
  }
  write_triangle_vtu(path, points, triangles, {{"displacement", displacement}}, {{"lip", lip}});
}

/// `e` with what to change in the case: a point covered by too few nodes (on its side of a cut, where the
/// enrichment or visibility removes the other side's) is a property of the cloud and the support, not a bug.
std::runtime_error with_support_hint(const meshless::SingularMomentMatrix& e, const core::Case& c) {
  return std::runtime_error(fmt::format(
      "{}. The node cloud does not determine the MLS approximation there{}. To cover every point with enough "
      "nodes: raise /meshless/support_factor (now {}; 2 couples each node to about 2.4x as many) or lower "
      "/meshless/node_spacing (now {} mm) (docs/MESHLESS.md §2, \"Support size\")",
      e.what(), c.cut ? ", on its side of the cut" : "", c.meshless.support_factor, c.meshless.node_spacing * 1e3));
}

bool is_direct(const meshless::EfgStatistics& st) {
  return st.linear_solver_kind == meshless::LinearSolverKind::direct ||
         st.linear_solver_kind == meshless::LinearSolverKind::direct_umfpack;
}

/// The linear solves' work in a step, in the solver's own terms: factorisations, or Krylov iterations and
/// preconditioner set-ups.
std::string linear_work(const meshless::StepRecord& rec, const meshless::EfgStatistics& st) {
  if (is_direct(st)) return fmt::format("{} factorisations", rec.factorisations);
  return fmt::format("{} Krylov iterations, {} preconditioner set-ups", rec.linear_iterations, rec.factorisations);
}

}  // namespace

std::string front_transition_hint(const core::InadmissibleStrain& e, const core::MeshlessSpec& spec,
                                  const std::optional<core::RuledSurface>& cut, double front_transition) {
  if (!cut) return {};
  const double to_front = cut->front_distance(e.point());
  if (to_front > spec.node_spacing) return {};
  const bool paper = spec.preset == core::MeshlessSpec::Preset::paper;
  const std::string where = fmt::format(
      "That point is {:.2f} mm from the cut's front, within one node spacing: the enrichment closes the cut there over "
      "ℓ = {:.2f} mm (/meshless/front_transition{}), and a sharp front concentrates the strain beside it. To stay "
      "inside the range: ",
      to_front * 1e3, front_transition * 1e3, paper ? ", fixed at 0 by /meshless/preset \"paper\"" : "");
  // The usual transition is a fifth of the spacing. Where ℓ is already that long, naming it again would send the
  // user round in a circle: a longer closing (measured: ℓ = 2.4 instead of 2 mm on a 12 mm cloud of lung_large
  // carried the solve from t = 1 s to 1.4 s) or a smaller force are what is left.
  const double usual = spec.node_spacing / 5.0;
  if (front_transition < 0.95 * usual)
    return where + fmt::format("{}set /meshless/front_transition to about node_spacing / 5 = {:.1f} mm, which closes "
                               "the cut over that distance (docs/MESHLESS.md §5.2)",
                               paper ? "leave the paper's preset (/meshless/preset \"default\") and " : "", usual * 1e3);
  return where + fmt::format("ℓ is already at least node_spacing / 5, so lengthen it (/meshless/front_transition = "
                             "{:.1f} mm closes the cut over twice the distance) or lower /load/force; the cloud does not "
                             "resolve the strain beside this front at this load (docs/MESHLESS.md §5.2)",
                             2.0 * front_transition * 1e3);
}

void set_up_meshless(meshless::EfgModel& model, const core::Case& c,
                     const std::function<void(const std::string&)>& on_step) {
  try {
    model.setup_system();
  } catch (const meshless::SingularMomentMatrix& e) {
    throw with_support_hint(e, c);
  }
  const meshless::EfgStatistics& st = model.statistics();
  if (on_step)
    on_step(fmt::format("EFG set up: {} nodes, {} cells, {} volume points ({:.1f} nodes each), alpha = {:.4g} Pa/m, "
                        "{} non-zeros, {}",
                        st.num_nodes, st.num_cells, st.num_volume_points, st.mean_nodes_per_point, st.alpha,
                        st.matrix_nonzeros, st.linear_solver));
}

ModelResult solve_meshless(const core::Case& c, const core::Geometry& g, const std::string& vtu_prefix,
                           const std::function<void(const std::string&)>& on_step,
                           const meshless::EfgOptions& options, bool progressive_cut) {
  const auto t_start = std::chrono::steady_clock::now();
  meshless::EfgProblem problem = meshless::problem_from_case(c, g);
  // A progressive incision starts with its first increment and advances at the start of the next steps.
  const int increments = progressive_cut && problem.cut ? c.cut->steps : 1;
  const std::optional<core::RuledSurface> full_cut = problem.cut;
  if (increments > 1) problem.cut = full_cut->truncated(full_cut->trace_length() / increments);
  meshless::EfgModel model(std::move(problem), options);
  set_up_meshless(model, c, on_step);
  return run_meshless_steps(model, c, g, vtu_prefix, on_step, {increments, full_cut, t_start, {}});
}

ModelResult run_meshless_steps(meshless::EfgModel& model, const core::Case& c, const core::Geometry& g,
                               const std::string& vtu_prefix, const std::function<void(const std::string&)>& on_step,
                               const MeshlessRun& run) {
  const auto t_start = run.start;
  const int increments = run.cut_increments;
  const std::optional<core::RuledSurface>& full_cut = run.full_cut;
  auto cut_after = [&](int k) { return full_cut->truncated(full_cut->trace_length() * k / increments); };
  const meshless::EfgStatistics& st = model.statistics();
  ModelResult r;
  r.model = "meshless";
  nlohmann::json cut_updates = nlohmann::json::array();
  const int n_steps = static_cast<int>(model.problem().step_times.size());
  const int every = std::max(1, c.output.every);
  for (int step = 1; step <= n_steps; ++step) {
    const auto t0 = std::chrono::steady_clock::now();
    if (step > 1 && step <= increments) {
      meshless::CutUpdate u;
      try {
        u = model.advance_cut(cut_after(step));  // paper §4: a local update
      } catch (const meshless::SingularMomentMatrix& e) {
        throw with_support_hint(e, c);
      }
      cut_updates.push_back({{"step", step},
                             {"cut_length_mm", model.problem().cut->trace_length() * 1e3},
                             {"volume_points_recomputed", u.volume_points_recomputed},
                             {"volume_points", u.volume_points},
                             {"boundary_points_recomputed", u.boundary_points_recomputed},
                             {"boundary_points", u.boundary_points},
                             {"modified_nodes", u.modified_nodes},
                             {"pairs_added", u.pairs_added},
                             {"tables_packed", u.tables_packed},
                             {"quadrature_seconds", u.quadrature_seconds},
                             {"shape_function_seconds", u.shape_function_seconds},
                             {"coupling_seconds", u.coupling_seconds},
                             {"seconds", u.seconds}});
      if (on_step)
        on_step(fmt::format("cut advanced to {:.1f} of {:.1f} mm: shape functions of {} of {} volume points "
                            "recomputed, {} node pairs added, in {:.2f} s",
                            model.problem().cut->trace_length() * 1e3, full_cut->trace_length() * 1e3,
                            u.volume_points_recomputed, u.volume_points, u.pairs_added, u.seconds));
    }
    meshless::StepRecord rec;
    try {
      rec = model.solve_step(step);
    } catch (const core::InadmissibleStrain& e) {
      const std::string hint = front_transition_hint(e, c.meshless, model.problem().cut, model.problem().front_transition);
      if (hint.empty()) throw;
      throw std::runtime_error(std::string(e.what()) + ". " + hint);
    }
    if (!vtu_prefix.empty() && c.output.vtu && (step % every == 0 || step == n_steps)) {
      // output_results: interpolated displacement u(X_i) = sum_j phi_j(X_i) U_j on the meshless cells (eq. 7)
      write_tet_vtu(fmt::format("{}_{:03d}.vtu", vtu_prefix, step), model.nodes(), g.meshless_mesh.tets,
                    {{"displacement", vector_field(model.nodal_displacements())}}, {});
      if (model.problem().cut) write_lips_vtu(fmt::format("{}_lips_{:03d}.vtu", vtu_prefix, step), model);
    }
    r.steps.push_back({rec.step, rec.time, seconds_since(t0), rec.assembly_seconds, rec.solve_seconds,
                       rec.newton_iterations, rec.residuals, rec.linear_iterations, rec.substeps,
                       rec.failed_attempts, rec.admissibility_margin, rec.retried_plain, rec.rejected_mixes});
    if (on_step)
      on_step(fmt::format("step {}/{} t = {:.3f} s: {} Newton iterations ({}), residual {:.2e}{}{}", step, n_steps,
                          rec.time, rec.newton_iterations, linear_work(rec, st), rec.residuals.back(),
                          !rec.reused_factorisation ? ""
                          : is_direct(st)           ? " (factorisation reused)"
                                                    : " (preconditioner reused)",
                          rec.cutbacks > 0 ? fmt::format(", {} cut-backs into {} sub-steps", rec.cutbacks, rec.substeps)
                                           : std::string()));
  }
  r.sample_points = g.sample_points;
  r.sample_displacements = model.displacements_at(g.sample_points);
  if (!r.sample_displacements.allFinite()) throw std::runtime_error("meshless: non-finite sample displacement");
  // This run's share of the model's timings (a restarted model's set-up was paid before the run).
  meshless::EfgTimings t = model.timings();
  t.setup_seconds -= run.timings_before.setup_seconds;
  t.shape_function_seconds -= run.timings_before.shape_function_seconds;
  t.assembly_seconds -= run.timings_before.assembly_seconds;
  t.solve_seconds -= run.timings_before.solve_seconds;
  r.setup_seconds = t.setup_seconds + t.shape_function_seconds;
  r.total_seconds = seconds_since(t_start);
  r.details["n_nodes"] = st.num_nodes;
  r.details["n_dofs"] = 3 * st.num_nodes;
  r.details["n_cells"] = st.num_cells;
  r.details["n_volume_points"] = st.num_volume_points;
  r.details["n_boundary_points"] = st.num_boundary_points;
  r.details["mean_nodes_per_point"] = st.mean_nodes_per_point;
  r.details["matrix_nonzeros"] = st.matrix_nonzeros;
  r.details["alpha_Pa_per_m"] = st.alpha;
  r.details["penalised_area_mm2"] = st.penalised_area * 1e6;
  r.details["load_area_mm2"] = st.loaded_area * 1e6;
  r.details["quadrature_order"] = c.meshless.quadrature_order;
  r.details["variationally_consistent_integration"] = model.problem().variationally_consistent;
  r.details["preset"] = c.meshless.preset_name();
  r.details["divergence_defect_before_vci"] = model.divergence_defect();
  r.details["linear_solver"] = st.linear_solver;
  r.details["umfpack_peak_memory_estimate_bytes"] = st.direct_peak_memory_estimate;
  r.details["umfpack_flops_estimate"] = st.direct_flops_estimate;
  r.details["available_memory_bytes"] = st.available_memory;
  r.details["nonlinear_solver"] =
      "Newton on the consistent tangent (core::KelvinLaw), reusing the factorised tangent while it contracts the residual";
  r.details["law_admissibility"] = admissibility_json(model.smallest_margin(), c.material);
  r.details["min_step_seconds"] = model.problem().min_step;
  if (model.problem().cut) {
    r.details["cut"] = {{"treatment", meshless::to_string(model.problem().cut_treatment)},
                        {"front_transition_mm", model.problem().front_transition * 1e3},
                        {"length_mm", model.problem().cut->trace_length() * 1e3},
                        {"lip_points", st.num_lip_points},
                        {"modified_nodes", st.num_cut_modified_nodes},
                        {"increments", increments},
                        {"updates", cut_updates}};
  }
  r.details["setup_seconds"] = t.setup_seconds;
  r.details["shape_function_seconds"] = t.shape_function_seconds;
  r.details["assembly_seconds"] = t.assembly_seconds;
  r.details["solve_seconds"] = t.solve_seconds;
  return r;
}

int run_verify_meshless(const std::string& out_dir, bool quick) {
  using nlohmann::json;
  const std::vector<int> orders = quick ? std::vector<int>{2, 3} : std::vector<int>{1, 2, 3, 4, 5};
  const std::vector<int> heights = quick ? std::vector<int>{2, 3, 4} : std::vector<int>{2, 3, 4, 6};
  Progress progress("verify meshless", 3 + 2 * static_cast<int>(orders.size()) + static_cast<int>(heights.size()) +
                                          (quick ? 0 : 9));
  core::OutputDirectory out(out_dir);
  json j;
  std::string md = "# Meshless (EFG) verification\n\nProduced by `tissue verify meshless`; see docs/MESHLESS.md.\n\n";

  progress.step("MLS invariants at random points");
  const meshless::InvariantReport inv = meshless::mls_invariants();
  j["invariants"] = {{"nodes", inv.num_nodes},
                     {"points", inv.num_points},
                     {"max_partition_of_unity_error", inv.max_partition_error},
                     {"max_linear_reproduction_error_over_h", inv.max_reproduction_error},
                     {"max_gradient_sum_times_h", inv.max_gradient_sum},
                     {"max_gradient_reproduction_error", inv.max_gradient_reproduction}};
  md += fmt::format(
      "## MLS invariants ({} random points, jittered {}-node cloud)\n\n| invariant | max error |\n|---|---|\n"
      "| Σφᵢ = 1 | {:.2e} |\n| Σφᵢxᵢ = x (÷h) | {:.2e} |\n| Σ∇φᵢ = 0 (×h) | {:.2e} |\n| Σxᵢ⊗∇φᵢ = I | {:.2e} |\n\n",
      inv.num_points, inv.num_nodes, inv.max_partition_error, inv.max_reproduction_error, inv.max_gradient_sum,
      inv.max_gradient_reproduction);

  md += "## Linear patch test (jittered 6³-node cube, penalty ū and σn on all faces)\n\n"
        "| quadrature order | max rel. error, plain eq. 22 | max rel. error, with VCI |\n|---|---|---|\n";
  json patch = json::array();
  for (int order : orders) {
    progress.step(fmt::format("patch test, quadrature order {} (plain)", order));
    const meshless::PatchTestReport plain = meshless::run_patch_test(order, false);
    progress.step(fmt::format("patch test, quadrature order {} (VCI)", order));
    const meshless::PatchTestReport vci = meshless::run_patch_test(order, true);
    patch.push_back({{"quadrature_order", order},
                     {"nodes", plain.num_nodes},
                     {"max_relative_error_plain", plain.max_relative_error},
                     {"max_relative_error_vci", vci.max_relative_error},
                     {"strain_relative_error_plain", plain.strain_relative_error},
                     {"strain_relative_error_vci", vci.strain_relative_error}});
    md += fmt::format("| {} | {:.3e} | {:.3e} |\n", order, plain.max_relative_error, vci.max_relative_error);
  }
  j["patch_test"] = patch;

  md += "\n## Cantilever vs Timoshenko (L = 100 mm, 20 × 20 mm, ν = 0, quadrature order 3, VCI)\n\n"
        "| h [mm] | nodes | L2 rel. error | energy rel. error | tip u_y / exact |\n|---|---|---|---|---|\n";
  json cant = json::array();
  std::vector<double> h, l2, en;
  for (int nd : heights) {
    progress.step(fmt::format("cantilever, {} cells through the height", nd));
    const meshless::CantileverReport r = meshless::run_cantilever(nd);
    h.push_back(r.node_spacing);
    l2.push_back(r.l2_error);
    en.push_back(r.energy_error);
    cant.push_back({{"h_mm", r.node_spacing * 1e3},
                    {"nodes", r.num_nodes},
                    {"l2_error", r.l2_error},
                    {"energy_error", r.energy_error},
                    {"tip_deflection_mm", r.tip_deflection * 1e3},
                    {"exact_tip_deflection_mm", r.exact_tip_deflection * 1e3},
                    {"seconds", r.seconds}});
    md += fmt::format("| {:.3f} | {} | {:.3e} | {:.3e} | {:.5f} |\n", r.node_spacing * 1e3, r.num_nodes, r.l2_error,
                      r.energy_error, r.tip_deflection / r.exact_tip_deflection);
  }
  const double rate_l2 = core::convergence_rate(h, l2), rate_en = core::convergence_rate(h, en);
  j["cantilever"] = {{"runs", cant}, {"rate_l2", rate_l2}, {"rate_energy", rate_en}};
  md += fmt::format("\nFitted rates: L2 {:.2f}, energy {:.2f} (required ≥ {} and ≥ {}).\n\n", rate_l2, rate_en,
                    meshless::kCantileverMinRateL2, meshless::kCantileverMinRateEnergy);

  progress.step("creep bar under a step load");
  const meshless::CreepReport cr = meshless::run_creep_bar(40);
  j["creep"] = {{"nodes", cr.num_nodes},        {"times", cr.times}, {"strain", cr.strain},
                {"exact", cr.exact},            {"max_relative_error", cr.max_relative_error}};
  md += fmt::format(
      "## Creep bar (40 × 10 × 10 mm, ν = 0, σ0 = 100 Pa step at t = 0, 40 steps of 0.1 s)\n\n"
      "Max relative error of u_x(L)/L against σ0/K1 + σ0/K2 (1 − e^(−K2 t/η)): **{:.3e}** (required < 1e-2).\n",
      cr.max_relative_error);

  if (!quick) {
    // The cut against the FEM crack (docs/MESHLESS.md §5): the opening of a mode-I crack in a block.
    progress.step("crack opening: FEM reference at 2 and 1.5 mm");
    std::size_t dofs_coarse = 0, dofs = 0;
    const std::vector<double> fem_coarse = fem_crack_opening(0.002, &dofs_coarse);
    const std::vector<double> fem = fem_crack_opening(0.0015, &dofs);
    const double fem_change = largest_difference_of_peak(fem_coarse, fem);
    double peak = 0.0;
    for (double o : fem) peak = std::max(peak, o);
    md += fmt::format(
        "## Crack opening against the FEM crack (block 40 × 20 × 20 mm, mode I, 20 × 10 mm surface crack)\n\n"
        "FEM reference (P2, duplicated-node crack): {} DOFs at 1.5 mm, peak opening {:.1f} µm; against {} DOFs at "
        "2 mm the opening profile changes by {:.2f} % of the peak.\n\n"
        "| treatment | node spacing [mm] | front transition l [mm] | nodes | mouth opening [µm] (FEM {:.1f}) | largest "
        "difference to the FEM, % of its peak |\n|---|---|---|---|---|---|\n",
        dofs, peak * 1e6, dofs_coarse, 100 * fem_change, fem.front() * 1e6);
    json runs = json::array();
    auto run = [&](meshless::CutTreatment treatment, double spacing, double transition) {
      progress.step(fmt::format("crack opening: EFG {} at {} mm, l = {} mm", meshless::to_string(treatment),
                                spacing * 1e3, transition * 1e3));
      int nodes = 0;
      const std::vector<double> efg = efg_crack_opening(treatment, spacing, transition, &nodes);
      const double difference = largest_difference_of_peak(efg, fem);
      md += fmt::format("| {} | {} | {:.3g} | {} | {:.1f} | {:.2f} |\n", meshless::to_string(treatment), spacing * 1e3,
                        transition * 1e3, nodes, efg.front() * 1e6, 100 * difference);
      runs.push_back({{"treatment", meshless::to_string(treatment)},
                      {"node_spacing_mm", spacing * 1e3},
                      {"front_transition_mm", transition * 1e3},
                      {"nodes", nodes},
                      {"opening_um", efg},
                      {"largest_difference_of_fem_peak", difference}});
    };
    for (double l_per_h : {0.0, 0.02, 0.125, 0.5, 1.0})
      run(meshless::CutTreatment::enrichment, 0.002, 0.002 * l_per_h);
    run(meshless::CutTreatment::enrichment, 0.0015, 0.0015 * core::MeshlessSpec::kFrontTransitionPerSpacing);
    run(meshless::CutTreatment::visibility, 0.002, 0.0);
    run(meshless::CutTreatment::visibility, 0.0015, 0.0);
    std::vector<double> fem_um;
    for (double o : fem) fem_um.push_back(o * 1e6);
    j["crack_opening"] = {{"fem_opening_um", fem_um},
                          {"fem_dofs", dofs},
                          {"fem_change_2_to_1.5_mm_of_peak", fem_change},
                          {"runs", runs}};
    md += "\nThe default front transition is 0, the paper's function (`/meshless/front_transition`).\n\n";
  }

  progress.step("writing meshless.json and meshless.md");
  write_text_file(out.file("meshless.json").string(), j.dump(2) + "\n");
  write_text_file(out.file("meshless.md").string(), md);
  out.commit();
  progress.done();
  std::cout << md;
  const bool ok = rate_l2 >= meshless::kCantileverMinRateL2 && rate_en >= meshless::kCantileverMinRateEnergy &&
                  cr.max_relative_error < 0.01;
  return ok ? 0 : 1;
}

}  // namespace experiments
