#include "experiments/models/lrpim/lrpim_case_model.hpp"

#include <fmt/format.h>

#include <iostream>

#include "core/output_directory.hpp"
#include "experiments/io/progress.hpp"
#include "meshless/lrpim/lrpim_case.hpp"
#include "meshless/lrpim/lrpim_verification.hpp"

namespace experiments {

std::string LrpimCaseModel::cannot_solve(const core::Case& c) const {
  return c.cut ? "the LRPIM model has no treatment of a cut (remove /cut, or drop lrpim from /compare/models)"
               : std::string();
}

namespace {

/// One progress line per converged step.
std::function<void(const meshless::lrpim::LrpimStepReport&)> step_reporter(const core::Case& c,
                                                                          const SolveRequest& request) {
  return [&c, &request](const meshless::lrpim::LrpimStepReport& s) {
    if (request.on_step)
      request.on_step(fmt::format("lrpim: step {}/{} t = {:.3f} s: {} Newton iterations, {} factorisations, "
                                  "residual {:.2e}",
                                  s.step, c.time.steps, s.time, s.newton_iterations, s.factorisations,
                                  s.residuals.empty() ? 0.0 : s.residuals.back()));
  };
}

/// The run as the comparator's result; `setup_seconds`: what this solve paid for set-up (0 after a one-off set-up).
ModelResult model_result(const std::string& name, const core::Geometry& g, const meshless::lrpim::LrpimCaseRun& run,
                         double setup_seconds) {
  ModelResult r;
  r.model = name;
  r.sample_points = g.sample_points;
  r.sample_displacements = run.sample_displacements;
  r.setup_seconds = setup_seconds;
  r.total_seconds = setup_seconds;
  for (const auto& s : run.steps) {
    StepTiming t;
    t.step = s.step;
    t.time = s.time;
    t.wall_seconds = s.wall_seconds;
    t.assembly_seconds = s.assembly_seconds;
    t.solve_seconds = s.solve_seconds;
    t.iterations = s.newton_iterations;
    t.residuals = s.residuals;
    t.rejected_mixes = s.rejected_mixes;
    r.steps.push_back(t);
    r.total_seconds += s.wall_seconds;
  }
  r.details = run.details;
  r.details["n_nodes"] = run.n_nodes;
  r.details["n_dofs"] = run.n_dofs;
  r.details["model_setup_seconds"] = run.setup_seconds;  // paid by this solve, or once for a LoadSeries
  describe_samples_near_cut(g, &r);
  return r;
}

/// LrpimCaseModel's series: one meshless::lrpim::LrpimModel, restarted under each force.
class LrpimLoadSeries final : public LoadSeries {
 public:
  LrpimLoadSeries(std::string name, core::Case prepared, const core::Geometry& g)
      : name_(std::move(name)),
        prepared_(std::move(prepared)),
        geometry_(g),
        model_(meshless::lrpim::lrpim_problem_from_case(prepared_, g)) {}
  double setup_seconds() const override { return model_.statistics().setup_seconds; }
  ModelResult solve(const core::Case& c, const SolveRequest& request) override {
    check_differs_only_in_force(prepared_, c);
    model_.restart(meshless::lrpim::lrpim_load_from_case(c, geometry_));
    return model_result(name_, geometry_, meshless::lrpim::run_lrpim_model(model_, c, geometry_, step_reporter(c, request)),
                        0.0);
  }

 private:
  std::string name_;
  core::Case prepared_;
  const core::Geometry& geometry_;
  meshless::lrpim::LrpimModel model_;
};

}  // namespace

ModelResult LrpimCaseModel::solve(const core::Case& c, const core::Geometry& g, const SolveRequest& request) const {
  if (request.on_step)
    request.on_step(fmt::format("lrpim: set-up ({} nodes: local quadrature and RPIM tabulation)",
                                g.meshless_mesh.num_vertices()));
  meshless::lrpim::LrpimCaseOptions options;
  options.on_step = step_reporter(c, request);
  const meshless::lrpim::LrpimCaseRun run = meshless::lrpim::run_lrpim_case(c, g, options);
  return model_result(name(), g, run, run.setup_seconds);
}

std::unique_ptr<LoadSeries> LrpimCaseModel::prepare_load_series(const core::Case& c, const core::Geometry& g) const {
  // A cut case is refused by lrpim_problem_from_case (core::CaseError at /cut), as in solve().
  return std::make_unique<LrpimLoadSeries>(name(), c, g);
}

namespace {

std::string figure(const nlohmann::json& v) {
  if (v.is_number_float()) return fmt::format("{:.3g}", v.get<double>());
  return v.dump();
}

/// One line per figure of a verification item: its value and, where the item has one, its bound.
std::string item_md(const std::string& title, const nlohmann::json& item) {
  std::string md = fmt::format("## {} ({})\n\n| figure | value | bound |\n|---|---|---|\n", title,
                               item.value("passed", true) ? "passed" : "FAILED");
  const nlohmann::json bounds = item.value("bounds", nlohmann::json::object());
  for (const auto& [key, value] : item.items()) {
    if (key == "bounds" || key == "passed" || key == "levels") continue;
    md += fmt::format("| {} | {} | {} |\n", key, figure(value), bounds.contains(key) ? figure(bounds[key]) : "");
  }
  if (item.contains("levels")) {
    md += "\n| level | nodes | L2 | energy | tip / exact |\n|---|---|---|---|---|\n";
    for (const auto& l : item["levels"])
      md += fmt::format("| {} | {} | {:.4f} | {:.4f} | {:.3f} |\n", l["cells_through_height"].get<int>(),
                        l["nodes"].get<int>(), l["l2"].get<double>(), l["energy"].get<double>(),
                        l["tip_over_exact"].get<double>());
  }
  return md + "\n";
}

}  // namespace

int run_verify_lrpim(const std::string& out_dir, bool quick) {
  Progress progress("verify lrpim", 2);
  core::OutputDirectory out(out_dir);  // staged: nothing is left behind if anything below fails
  progress.step(quick ? "invariants, patch tests, cantilever (2, 3 cells), creep bars (quick)"
                      : "invariants, patch tests, cantilever (2, 3, 4 cells), creep bars");
  const nlohmann::json v = meshless::lrpim::run_lrpim_verification(quick);
  std::string md = fmt::format("# LRPIM verification{}\n\nProduced by `tissue verify lrpim{}` in {:.0f} s; see "
                               "docs/LRPIM.md §4. Overall: **{}**.\n\n",
                               quick ? " (quick)" : "", quick ? " --quick" : "", v["seconds"].get<double>(),
                               v["passed"].get<bool>() ? "passed" : "FAILED");
  for (const auto& [key, title] : std::vector<std::pair<std::string, std::string>>{
           {"rpim_invariants", "RPIM shape functions: partition of unity, linear reproduction, Kronecker delta"},
           {"patch_test_box", "Linear patch test, box body"},
           {"patch_test_cloud_surface", "Linear patch test, the cloud's boundary triangles as the body"},
           {"cantilever", "Timoshenko cantilever: convergence rates"},
           {"creep_bar_k0", "Creep bar, k = 0: the SLS closed form"},
           {"creep_bar_k2", "Creep bar, k = 2: the closed form of the nonlinear law"}})
    if (v.contains(key)) md += item_md(title, v[key]);
  if (v.contains("patch_test_uncorrected"))
    md += fmt::format("Without the divergence correction the box patch test leaves {:.3g} (reported, not a pass "
                      "condition).\n",
                      v["patch_test_uncorrected"]["displacement"].get<double>());
  progress.step("writing lrpim.json and lrpim.md");
  write_text_file(out.file("lrpim.json").string(), v.dump(2) + "\n");
  write_text_file(out.file("lrpim.md").string(), md);
  out.commit();
  progress.done();
  std::cout << md;
  return v["passed"].get<bool>() ? 0 : 1;
}

}  // namespace experiments
