#include "experiments/studies/reproduce.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <thread>

#include "core/case.hpp"
#include "core/geometry.hpp"
#include "core/json_reader.hpp"
#include "core/openblas_kernel.hpp"
#include "core/output_directory.hpp"
#include "experiments/comparator/compare.hpp"
#include "experiments/studies/cloud_change.hpp"
#include "experiments/io/child_process.hpp"
#include "experiments/io/side_by_side.hpp"
#include "experiments/models/model_registry.hpp"
#include "experiments/models/model_result.hpp"
#include "experiments/io/progress.hpp"
#include "meshless/efg/efg_problem.hpp"
#include "meshless/surrogate/surrogate.hpp"
#include "meshless/surrogate/surrogate_builder.hpp"
#include "meshless/surrogate/surrogate_file.hpp"

namespace experiments {

using json = nlohmann::json;

namespace {

json read_json_file(const std::string& file) {
  std::ifstream in(file);
  if (!in) throw core::CaseError(file, "", "a readable JSON file (it could not be opened)");
  try {
    return json::parse(in);
  } catch (const json::parse_error& e) {
    throw core::CaseError(file, "", std::string("valid JSON (") + e.what() + ")");
  }
}

/// A path written in the plan, which is relative to the plan's folder.
std::filesystem::path relative_to_plan(const std::string& plan_file, const std::string& path) {
  return (std::filesystem::path(plan_file).parent_path() / std::filesystem::path(path)).lexically_normal();
}

/// A case path of the plan, relative to the plan's folder; it must exist.
std::string resolve_case(const core::JsonReader& r, const std::string& key, const std::string& plan_file) {
  const std::filesystem::path p = relative_to_plan(plan_file, r.string(key));
  if (!std::filesystem::is_regular_file(p))
    r.fail(key, fmt::format("a case file relative to the plan's folder ({} does not exist)", p.string()));
  return p.string();
}

/// The optional array `key` of paths of the plan, each relative to the plan's folder, resolved; empty when absent.
/// `items` and `item` name what they are in the errors ("sweep folders", "a sweep folder"); `must_exist` refuses a
/// path that does not exist (a missing cloud study is reported by the table instead, experiments/studies/cloud_change.hpp).
std::vector<std::string> plan_paths(const core::JsonReader& t, const std::string& key, const std::string& plan_file,
                                    const std::string& items, const std::string& item, bool must_exist) {
  std::vector<std::string> paths;
  if (!t.has(key)) return paths;
  const json& array = t.array(key, 1, fmt::format("a non-empty array of {} relative to the plan", items));
  for (std::size_t k = 0; k < array.size(); ++k) {
    const std::string at = fmt::format("{}/{}", key, k);
    if (!array[k].is_string() || array[k].get<std::string>().empty())
      t.fail(at, fmt::format("{} (a string, relative to the plan's folder)", item));
    const std::string path = relative_to_plan(plan_file, array[k].get<std::string>()).string();
    if (must_exist && !std::filesystem::exists(path))
      t.fail(at, fmt::format("an existing {} ({} does not exist)", item.substr(item.find(' ') + 1), path));
    paths.push_back(path);
  }
  return paths;
}

std::string number_or_dash(const json& v, const char* format) {
  return v.is_number() ? fmt::format(fmt::runtime(format), v.get<double>()) : std::string("–");
}

/// The first model of a row whose role is of `kind` ("proposed", "baseline"), or null.
const json* model_with_role(const json& row, const std::string& kind) {
  for (const json& m : row.at("models"))
    if (role_kind(m.at("role").get<std::string>()) == kind && !m.contains("not_solved")) return &m;
  return nullptr;
}

/// The models of every row, in first-seen order: one column each.
std::vector<std::pair<std::string, std::string>> table1_columns(const json& rows) {
  std::vector<std::pair<std::string, std::string>> columns;  // name, role kind
  for (const json& r : rows)
    for (const json& m : r.at("models")) {
      const std::string name = m.at("name");
      if (std::none_of(columns.begin(), columns.end(), [&](const auto& c) { return c.first == name; }))
        columns.emplace_back(name, role_kind(m.at("role").get<std::string>()));
    }
  return columns;
}

/// The row's cloud change from the plan's cloud studies (experiments/studies/cloud_change.hpp), of the RMSEs against
/// the solved reference or (`versus_extrapolated`) against the extrapolated samples.
CloudChange row_cloud_change(const ReproducePlan::Table1Case& t, const json& row, bool versus_extrapolated) {
  const json* p = model_with_role(row, "proposed");
  const json* b = model_with_role(row, "baseline");
  const json& converged = row.at("versus_extrapolated");
  CloudChange none;
  if (!p || !b) {
    none.why_unknown = "the case has no solved proposed model and baseline";
    return none;
  }
  if (!versus_extrapolated)
    return cloud_change(t.cloud_studies, {p->at("name"), b->at("name"), p->at("rmse_mm").get<double>(),
                                          b->at("rmse_mm").get<double>(), row.at("peak_reference_mm").get<double>()});
  if (!converged.is_object()) {
    none.why_unknown = "no RMSEs against the extrapolated FEM in this row";
    return none;
  }
  const json& m = converged.at("models");
  CloudChangeBaseline baseline{p->at("name"), b->at("name"),
                               m.at(p->at("name").get<std::string>()).at("rmse_mm").get<double>(),
                               m.at(b->at("name").get<std::string>()).at("rmse_mm").get<double>(),
                               row.at("peak_reference_mm").get<double>()};
  baseline.versus_extrapolated = true;
  baseline.extrapolated_bar_mm = converged.at("error_bar_mm").get<double>();
  return cloud_change(t.cloud_studies, baseline);
}

}  // namespace

json table1_row(const ReproducePlan::Table1Case& t, const json& summary) {
  json models = json::array();
  json versus_extrapolated = summary.value("versus_extrapolated", json());
  if (versus_extrapolated.is_object())  // the solved reference's own distance, which the summary keeps with it
    versus_extrapolated["solved_reference_rmse_mm"] = summary.at("reference").at("solved_minus_extrapolated_rms_mm");
  for (const auto& [name, m] : summary.at("models").items())
    models.push_back({{"name", name},
                      {"role", m.value("role", std::string())},
                      {"rmse_mm", m.at("rmse_mm")},
                      {"relative", m.at("rmse_relative_to_peak")},
                      {"unflagged_mm", m.at("rmse_unflagged_mm")},
                      {"seconds", m.at("timings").is_object() ? m.at("timings").at("total_seconds") : json(nullptr)}});
  // A named copy: a range-for over items() of the temporary that value() returns would read it after its end.
  const json not_solved = summary.value("not_solved", json::object());
  for (const auto& [name, n] : not_solved.items())
    models.push_back({{"name", name}, {"role", n.at("role")}, {"not_solved", n.at("why")}});
  return {{"label", t.label},
          {"config", t.config},
          {"reference", summary.at("reference").at("model")},
          {"peak_reference_mm", summary.at("reference").at("peak_sample_displacement_mm")},
          {"models", models},
          {"difference_mm", summary.value("difference_mm", json())},
          {"difference_definition", summary.value("difference_definition", json())},
          {"flagged_samples", summary.at("flagged_samples")},
          {"reference_error_bar", summary.at("reference").at("error_bar")},
          {"cut_effect", summary.value("cut_effect", json())},
          {"versus_extrapolated", versus_extrapolated},
          {"paper_enrichment_mm", t.paper_enrichment_mm},
          {"paper_visibility_mm", t.paper_visibility_mm},
          {"paper_difference_mm", t.paper_enrichment_mm - t.paper_visibility_mm}};
}

std::string table1_verdict(const json& r) {
  const json* proposed = model_with_role(r, "proposed");
  const json* baseline = model_with_role(r, "baseline");
  if (!proposed || !baseline || !r.at("difference_mm").is_number()) return "no proposed model and baseline to compare";
  const double difference = r.at("difference_mm").get<double>();
  if (difference == 0.0) return "no cut: the two variants are one model";
  const std::string p = proposed->at("name"), b = baseline->at("name");
  const std::string closer = difference < 0 ? p : b;
  std::string effect;
  if (!r.at("cut_effect").is_null()) {
    const json& m = r.at("cut_effect").at("models");
    if (m.contains(p) && m.contains(b))
      effect = fmt::format("; on the cut's own effect {} is closer",
                           m.at(p).at("rmse_mm").get<double>() < m.at(b).at("rmse_mm").get<double>() ? p : b);
  }
  const json& bar = r.at("reference_error_bar");
  if (!bar.value("known", false)) return closer + " closer" + effect + "; significance unknown (no error bar)";
  const double bar_mm = bar.at("rms_mm").get<double>();
  const json cloud = r.value("cloud_change", json::object());
  const bool with_cloud = cloud.value("known", false);
  const double cloud_mm = with_cloud ? cloud.at("mm").get<double>() : 0.0;
  const auto significance = [](double ratio) {
    return ratio > 2.0 ? "significant" : ratio > 1.0 ? "marginal" : "not significant";
  };
  // A ratio below 0.1 keeps two decimals: "0.0×" would read as no difference at all.
  const auto times = [](double ratio) { return fmt::format(ratio < 0.1 ? "{:.2f}×" : "{:.1f}×", ratio); };
  const double ratio = std::abs(difference) / std::hypot(bar_mm, cloud_mm);
  std::string verdict = fmt::format("{} closer{}; the difference is {} {}: {}", closer, effect, times(ratio),
                                    with_cloud ? "the reference's bar and the cloud change combined"
                                               : "the reference's bar (the cloud change is not measured)",
                                    significance(ratio));
  // The same judgement against the converged FEM, whose bar is the study's finest level's: the solved reference's
  // own error can favour one variant (docs/EXPERIMENTS.md, "The extrapolated reference").
  const json converged = r.value("versus_extrapolated", json());
  if (converged.is_object() && converged.at("models").contains(p) && converged.at("models").contains(b)) {
    const double d = converged.at("models").at(p).at("rmse_mm").get<double>() -
                     converged.at("models").at(b).at("rmse_mm").get<double>();
    // Its cloud change from the same clouds' RMSEs against the extrapolated samples; where the kept runs lack them,
    // the change against the solved reference stands in, and the verdict says so.
    const json cloud_x = r.value("cloud_change_versus_extrapolated", json::object());
    const bool with_cloud_x = cloud_x.value("known", false);
    const double cloud_x_mm = with_cloud_x ? cloud_x.at("mm").get<double>() : cloud_mm;
    const double r_converged = std::abs(d) / std::hypot(converged.at("error_bar_mm").get<double>(), cloud_x_mm);
    verdict += fmt::format("; against the extrapolated FEM {} closer by {:.4f} mm, {} {}: {}", d < 0 ? p : b,
                           std::abs(d), times(r_converged),
                           with_cloud_x ? "their bar and the cloud change against them combined"
                           : with_cloud ? "their bar and the cloud change against the solved reference combined"
                                        : "their bar",
                           significance(r_converged));
  }
  return verdict;
}

namespace {

/// Table 1's "against the extrapolated FEM" cell: each model's RMSE against the mesh study's extrapolated samples,
/// their bar and how far the solved reference is from them; "–" without them (no study, or the reference is already
/// the extrapolated one).
std::string versus_extrapolated_cell(const json& v) {
  if (!v.is_object()) return "–";
  std::string cell;
  for (const auto& [name, m] : v.at("models").items())
    cell += fmt::format("{}{} {:.4f} ({:.1f} %)", cell.empty() ? "" : ", ", name, m.at("rmse_mm").get<double>(),
                        100 * m.at("rmse_relative_to_peak").get<double>());
  return cell + fmt::format("; their bar {:.4f} mm; the solved reference {:.4f} mm from them",
                            v.at("error_bar_mm").get<double>(), v.at("solved_reference_rmse_mm").get<double>());
}

/// The timing case with the plan's models (ReproducePlan::Timing::models; empty: the case's own list).
core::Case with_timed_models(const core::Case& base, const std::vector<std::string>& models) {
  if (models.empty()) return base;
  json doc = base.document;
  doc["compare"]["models"] = models;
  return core::parse_case(doc, base.source_file);
}

/// The timing case at force magnitude `magnitude` along the case's force direction, with `steps` time steps.
core::Case case_at_force(const core::Case& base, double magnitude, int steps) {
  json doc = base.document;
  const Eigen::Vector3d direction = base.load.force.normalized();
  doc["load"]["force"] = {magnitude * direction(0), magnitude * direction(1), magnitude * direction(2)};
  doc["time"]["steps"] = steps;
  if (doc.contains("cut") && doc["cut"].contains("steps")) doc["cut"]["steps"] = 1;
  doc["output"]["vtu"] = false;
  return core::parse_case(doc, base.source_file);
}

double peak_sample_mm(const Eigen::MatrixXd& u) { return u.rowwise().norm().maxCoeff() * 1e3; }

int newton_iterations(const ModelResult& r) {
  int n = 0;
  for (const StepTiming& s : r.steps) n += s.iterations;
  return n;
}

/// Queries timed per force (their median is reported): enough to smooth out the scheduler's interruptions.
constexpr int kQueriesPerForce = 2001;

/// The models of the Fig. 9 analogue: the timing case's reference and scored models that solve it, without the
/// floor (it takes no time) and without a model that is another's on this case (Model::same_as).
std::vector<std::unique_ptr<Model>> timed_models(const core::Case& c) {
  std::vector<std::unique_ptr<Model>> timed;
  for (auto& m : models_of_case(c)) {
    if (role_kind(m->role()) == "floor" || !m->cannot_solve(c).empty()) continue;
    const std::string same = m->same_as(c);
    if (!same.empty() && std::any_of(timed.begin(), timed.end(), [&](const auto& t) { return t->name() == same; }))
      continue;
    timed.push_back(std::move(m));
  }
  return timed;
}

/// Each timed model prepared for the forces (Model::prepare_load_series), or why it could not be.
struct TimedSeries {
  const Model* model = nullptr;
  std::unique_ptr<LoadSeries> series;  ///< null when preparing failed
  std::string error;
};

/// One force: every timed model's solve on its series (the geometry is shared, and a model that sets up once did so
/// before the first force), or its error. "seconds" is the full time of one result: the one-off set-up plus this
/// force's solve, or the whole run when the model sets up per solve; "solve_seconds" leaves the set-up out.
json time_one_force(const core::Case& c, double force, std::vector<TimedSeries>& timed, Progress* progress) {
  json row = {{"force_N", force}, {"models", json::object()}};
  for (TimedSeries& t : timed) {
    const std::string name = t.model->name();
    if (!t.series) {
      row["models"][name] = {{"error", t.error}};
      continue;
    }
    try {
      progress->step(fmt::format("{:.2f} N: {}, full solve", force, name));
      const ModelResult r = t.series->solve(c, SolveRequest{});
      const double once = t.series->setup_seconds();
      row["models"][name] = {{"seconds", once + r.total_seconds},
                             {"solve_seconds", r.total_seconds - r.setup_seconds},
                             {"setup_seconds", once > 0.0 ? once : r.setup_seconds},
                             {"setup_once", once > 0.0},
                             {"newton_iterations", newton_iterations(r)},
                             {"peak_sample_mm", peak_sample_mm(r.sample_displacements)}};
    } catch (const std::exception& e) {
      row["models"][name] = {{"error", e.what()}};
    }
  }
  return row;
}

/// The surrogate of `config`, trained here (as `tissue fit` does) or, when `trained_file` is given, read from the file
/// `tissue fit` wrote beside Table 1 (checked against the case's hash), then queried at `stressed`'s load point for
/// each force along its force direction: the median wall time of a query over many repetitions, and the answer.
json time_surrogate(const std::string& config, const core::Case& stressed, const std::vector<double>& forces,
                    const std::string& trained_file, Progress* progress) {
  const core::Case c = core::load_case(config);
  std::optional<meshless::Surrogate> surrogate;
  int training_solves = 0;
  double training_seconds = 0.0;
  std::string trained;
  if (trained_file.empty()) {
    progress->step(fmt::format("timing: training the surrogate of {} ({} full solves, as tissue fit)", config,
                               6 * c.surrogate.contact_points.size() * c.surrogate.force_levels));
    const auto t0 = std::chrono::steady_clock::now();
    core::GeometryOptions geometry;
    geometry.build_fem_mesh = false;
    const core::Geometry g = core::build_geometry(c, geometry);
    meshless::SurrogateBuildReport report;
    surrogate.emplace(meshless::build_surrogate(meshless::problem_from_case(c, g), c.surrogate, {}, {}, &report));
    training_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    training_solves = report.training_solves;
    trained = "here, before the queries (geometry included)";
  } else {
    meshless::SurrogateData data = meshless::read_surrogate(trained_file, meshless::surrogate_case_hash(c));
    const json& report = data.report;
    training_solves = report.at("training").at("solves").get<int>();
    training_seconds = report.at("training").at("wall_seconds").get<double>() +
                       report.at("fit_seconds").get<double>() + report.at("holdout_wall_seconds").get<double>();
    trained = fmt::format("by `tissue fit` at one thread while Table 1 ran (training, fits and held-out checks; "
                          "{})", std::filesystem::path(trained_file).filename().string());
    surrogate.emplace(std::move(data));
  }

  progress->step(fmt::format("timing: {} surrogate queries per force", kQueriesPerForce));
  const json rows = surrogate_query_timing(*surrogate, stressed.load.point, stressed.load.force.normalized(), forces,
                                           kQueriesPerForce);
  return {{"status", "measured"},
          {"config", config},
          {"node_spacing_mm", 1e3 * c.meshless.node_spacing},
          {"surface_nodes", surrogate->num_surface_nodes()},
          {"training_solves", training_solves},
          {"training_seconds", training_seconds},
          {"trained", trained},
          {"queries_per_force", kQueriesPerForce},
          {"rows", rows}};
}

std::string surrogate_cell(const json& surrogate, std::size_t row) {
  if (surrogate.at("status") != "measured") return surrogate.at("status").get<std::string>();
  const json& r = surrogate.at("rows").at(row);
  std::string flags;
  if (!r.at("force_in_range").get<bool>()) flags += ", force clamped to the trained range";
  if (!r.at("on_trained_contact").get<bool>()) flags += ", off the trained contact";
  return fmt::format("{:.1f} µs (|u| = {:.3f} mm{})", 1e6 * r.at("seconds").get<double>(),
                     r.at("contact_displacement_mm").get<double>(), flags);
}

std::string timing_cell(const json& model) {
  if (model.contains("error")) return "failed: " + model.at("error").get<std::string>();
  const std::string split =
      model.value("setup_once", false)
          ? fmt::format(" = {:.2f} s set-up once + {:.2f} s", model.at("setup_seconds").get<double>(),
                        model.at("solve_seconds").get<double>())
          : std::string();
  return fmt::format("{:.2f} s{} ({} Newton, peak {:.3f} mm)", model.at("seconds").get<double>(), split,
                     model.at("newton_iterations").get<int>(), model.at("peak_sample_mm").get<double>());
}

/// "a / b" of two models' `key` seconds in one row ("seconds": full; "solve_seconds": without the set-up), or a
/// dash when either failed.
std::string seconds_ratio(const json& a, const json& b, const std::string& key = "seconds") {
  return a.contains(key) && b.contains(key)
             ? fmt::format("{:.2f}", a.at(key).get<double>() / b.at(key).get<double>())
             : std::string("–");
}

void plot_timing(const core::OutputDirectory& out, json* timing) {
  const std::string log = out.file("plot_timing.log").string();
  const ProcessOutcome p = run_process({plot_python(), std::string(TISSUE_SOURCE_DIR) + "/scripts/plot_timing.py",
                                        out.file("timing.json").string(), out.file("timing.png").string()},
                                       log);
  if (p.ok()) {
    std::filesystem::remove(log);
    (*timing)["timing_png"] = "timing.png";
    return;
  }
  std::filesystem::remove(out.file("timing.png"));
  std::cerr << "warning: timing.png not written (" << p.error << "); see plot_timing.log\n";
  (*timing)["timing_png"] = nullptr;
  (*timing)["plot_error"] = p.error;
}

}  // namespace

std::string table1_md(const json& rows) {
  const auto columns = table1_columns(rows);
  std::string md = "# Table 1: RMSE of the sample displacements against the FEM reference (eq. 34)\n\n| case |";
  std::string rule = "|---|";
  for (const auto& [name, kind] : columns) {
    md += fmt::format(" {} ({}) [mm] |", name, kind);
    rule += "---|";
  }
  md += " difference [mm] | without flagged samples [mm] | cut effect RMSE [mm] | reference error bar | against the "
        "extrapolated FEM [mm] | meshless cloud change [mm] | verdict | paper: proposed / baseline / difference [mm] "
        "|\n" + rule + "---|---|---|---|---|---|---|---|\n";
  for (const json& r : rows) {
    const auto find = [&](const std::string& name) -> const json* {
      for (const json& m : r.at("models"))
        if (m.at("name") == name) return &m;
      return nullptr;
    };
    md += "| " + r.at("label").get<std::string>() + " |";
    std::string unflagged, effect;
    for (const auto& [name, kind] : columns) {
      const json* m = find(name);
      if (!m) {
        md += " – |";
        continue;
      }
      if (m->contains("not_solved")) {  // a model that cannot solve the case, or whose solve failed (its error below)
        md += m->at("not_solved").get<std::string>().rfind("failed", 0) == 0 ? " failed |" : " not solved |";
        continue;
      }
      md += fmt::format(" {:.4f} ({:.1f} %) |", m->at("rmse_mm").get<double>(), 100 * m->at("relative").get<double>());
      unflagged += fmt::format("{}{} {}", unflagged.empty() ? "" : ", ", name,
                               number_or_dash(m->at("unflagged_mm"), "{:.4f}"));
      const json& e = r.at("cut_effect");
      if (!e.is_null() && e.at("models").contains(name)) {
        const json& em = e.at("models").at(name);
        effect += fmt::format("{}{} {:.4f} ({:.1f} %)", effect.empty() ? "" : ", ", name, em.at("rmse_mm").get<double>(),
                              100 * em.value("rmse_relative_to_fem_peak", 0.0));
      }
    }
    const json& bar = r.at("reference_error_bar");
    const std::string error_bar = bar.value("known", false)
                                      ? fmt::format("{:.3f} mm ({})", bar.at("rms_mm").get<double>(),
                                                    bar.value("method", std::string()))
                                      : "unknown: " + bar.value("why_unknown", std::string());
    const json cloud = r.value("cloud_change", json::object());
    const std::string converged = versus_extrapolated_cell(r.value("versus_extrapolated", json()));
    const auto change_text = [](const json& change) {
      return fmt::format("{:.4f} ({})", change.at("mm").get<double>(), change.at("measure").get<std::string>());
    };
    const json cloud_x = r.value("cloud_change_versus_extrapolated", json::object());
    std::string cloud_change = cloud.value("known", false) ? change_text(cloud) : "–";
    if (cloud_x.value("known", false)) cloud_change += "; against the extrapolated FEM " + change_text(cloud_x);
    md += fmt::format(" {} | {} | {} | {} | {} | {} | {} | {:.2f} / {:.2f} / {:+.2f} |\n",
                      number_or_dash(r.at("difference_mm"), "{:+.4f}"), unflagged.empty() ? "–" : unflagged,
                      effect.empty() ? "–" : effect, error_bar, converged, cloud_change, table1_verdict(r),
                      r.at("paper_enrichment_mm").get<double>(), r.at("paper_visibility_mm").get<double>(),
                      r.at("paper_difference_mm").get<double>());
  }
  for (const json& r : rows)
    for (const auto& [key, title] : {std::pair<std::string, std::string>{"cloud_change", "the meshless cloud change"},
                                     {"cloud_change_versus_extrapolated",
                                      "the meshless cloud change against the extrapolated FEM"}}) {
    const json cloud = r.value(key, json::object());
    if (cloud.value("known", false)) {
      std::string runs;
      for (const json& run : cloud.at("runs")) {
        std::string models;
        for (const auto& [name, v] : run.items())
          if (v.is_object())
            models += fmt::format("{}{} {}", models.empty() ? "" : ", ", name,
                                  v.contains("rmse_mm") ? fmt::format("{:.4f} mm ({} nodes)", v.at("rmse_mm").get<double>(),
                                                                      v.at("n_nodes").dump())
                                                        : std::string("not solved"));
        runs += fmt::format("\n- {}: {}", run.at("run").get<std::string>(),
                            run.contains("unused") ? "unused, " + run.at("unused").get<std::string>() : models);
      }
      md += fmt::format("\n{}: {}, from the kept runs of its cloud studies:{}\n", r.at("label").get<std::string>(),
                        title, runs);
    }
  }
  for (const json& r : rows)
    for (const json& m : r.at("models"))
      if (m.contains("not_solved"))
        md += fmt::format("\n{}, {}: {}.\n", r.at("label").get<std::string>(), m.at("name").get<std::string>(),
                          m.at("not_solved").get<std::string>());
  md += "\nThe paper's Table 1 is for its own lung models (§5.4); ours are the lung cases named in the plan, on another "
        "lung, support and load, so compare the ranking and the relative size of the models, not the millimetres. "
        "One column per model of each case's /compare list, with its role: proposed (the paper's model), baseline "
        "(the paper's interactive meshless cutting model), other meshless models, and the floor (the undeformed body: "
        "its RMSE is the reference's own RMS displacement, which any model must beat). The difference is the "
        "proposed model's RMSE minus the baseline's. The cut effect is each model's cut solve minus its own uncut "
        "solve, compared with the FEM's, so that the meshless model's common discretisation error does not decide "
        "which cut treatment wins. The meshless cloud change is how far the difference moves when only the node cloud "
        "changes (the plan's cloud_studies; where the proposed model solves on no other cloud, the largest change of "
        "one model's RMSE stands in for it). The reference's error bar comes from the committed mesh study its cell "
        "names: results/verify/fem.json, which solved this very reference as its coarsest level, or (the plan's "
        "reference_family) studies of the same problem in another mesh family, averaged over the meshes beside each "
        "level. Against the extrapolated FEM: each model's RMSE against the samples that study extrapolated from "
        "its two finest levels, whose bar (their estimated error) is far smaller than that of the solved reference: "
        "how far each model is from the converged FEM. The verdict's significance sets the difference of the RMSEs against the "
        "reference's error bar (RMS) and the cloud change combined, sqrt(bar² + change²): above 2× significant, 1–2× "
        "marginal; then the same against the extrapolated FEM, with their bar. Each case's full comparison (per-sample "
        "errors, flags, timings, radar diagram) is in its sub-folder.\n";
  if (!rows.empty() && rows.front().contains("run"))
    md += fmt::format("\nThe cases ran {}: the times in their sub-folders are of that run; timing.md's, measured "
                      "alone, are the speed figures.\n", rows.front().at("run").get<std::string>());
  return md;
}

std::string timing_md(const json& timing) {
  const json& models = timing.at("models");
  std::string proposed, reference;  // the ratio columns' models: the first of each role
  for (const json& m : models) {
    const std::string kind = role_kind(m.at("role").get<std::string>());
    if (kind == "proposed" && proposed.empty()) proposed = m.at("name");
    if (kind == "reference" && reference.empty()) reference = m.at("name");
  }
  std::string md = fmt::format(
      "# Fig. 9 analogue: the time to compute one deformation result\n\n"
      "Case `{}`, {} time step(s) per result, forces along the case's force direction at its load point. Each "
      "time is what one result costs: the model's set-up, assembly and solves, geometry excluded (built once: "
      "{:.1f} s). The meshless models set up once for every force on this cloud, as a simulator would (the LRPIM "
      "its local quadrature and RPIM functions, the EFG its MLS functions and pattern; each force then factorises "
      "its own tangent), and their time is that set-up plus this force's solve (`= set-up once + solve`); the FEM "
      "sets up in each run. The `solves` ratio leaves the set-up out."
      "\n\n| force [N] |",
      timing.at("config").get<std::string>(), timing.at("steps").get<int>(),
      timing.at("geometry_seconds").get<double>());
  std::string rule = "|---|";
  for (const json& m : models) {
    md += fmt::format(" {} ({}), full solve |", m.at("name").get<std::string>(),
                      role_kind(m.at("role").get<std::string>()));
    rule += "---|";
  }
  const bool ratio = !proposed.empty() && !reference.empty();
  if (ratio) md += fmt::format(" {} / {} |", proposed, reference);
  for (const json& m : models)
    if (m.at("name") != proposed && m.at("name") != reference && !proposed.empty())
      md += fmt::format(" {0} / {1} | {0} / {1}, solves |", m.at("name").get<std::string>(), proposed);
  md += " surrogate query |";
  if (!proposed.empty()) md += fmt::format(" {} / surrogate |", proposed);
  const int extra = (ratio ? 1 : 0) + 1 + (proposed.empty() ? 0 : 1) +
                    (proposed.empty() ? 0
                                      : 2 * static_cast<int>(std::count_if(models.begin(), models.end(), [&](const json& m) {
                                          return m.at("name") != proposed && m.at("name") != reference;
                                        })));
  for (int i = 0; i < extra; ++i) rule += "---|";
  md += "\n" + rule + "\n";
  const json& surrogate = timing.at("surrogate");
  const bool measured = surrogate.at("status") == "measured";
  const json& rows = timing.at("rows");
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const json& row = rows[i].at("models");
    md += fmt::format("| {:.2f} |", rows[i].at("force_N").get<double>());
    for (const json& m : models) md += " " + timing_cell(row.at(m.at("name").get<std::string>())) + " |";
    if (ratio) md += " " + seconds_ratio(row.at(proposed), row.at(reference)) + " |";
    for (const json& m : models)
      if (m.at("name") != proposed && m.at("name") != reference && !proposed.empty()) {
        const json& other = row.at(m.at("name").get<std::string>());
        md += " " + seconds_ratio(other, row.at(proposed)) + " | " +
              seconds_ratio(other, row.at(proposed), "solve_seconds") + " |";
      }
    md += " " + surrogate_cell(surrogate, i) + " |";
    if (!proposed.empty()) {
      const json& p = row.at(proposed);
      md += " " + (measured && p.contains("seconds")
                       ? fmt::format("{:.3g}", p.at("seconds").get<double>() /
                                                   surrogate.at("rows").at(i).at("seconds").get<double>())
                       : std::string("–")) + " |";
    }
    md += "\n";
  }
  md += "\nThe ratios are measured in this run, on this machine: compare them, not the absolute seconds. The models "
        "are the plan's /timing/models, or else the timing case's /compare list (docs/CONFIG.md), without the "
        "floor.";
  const std::string kernels = timing.value("openblas_kernels", std::string());
  md += kernels.empty() ? std::string(" The BLAS is not OpenBLAS.\n")
                        : fmt::format(" The factorisations ran on OpenBLAS's {} kernels (docs/PERFORMANCE.md, "
                                      "\"BLAS\").\n",
                                      kernels);
  if (measured)
    md += fmt::format(
        "\nThe surrogate (paper §3, docs/SURROGATE.md) is trained on `{}` ({:.0f} mm node spacing, {} surface "
        "nodes), once, in {} full solves and {:.1f} s, {}; a query is the median of {} calls, answering the contact "
        "displacement and every surface node's. |u| is its contact node's displacement at the end of its "
        "training ramp.\n",
        surrogate.at("config").get<std::string>(), surrogate.at("node_spacing_mm").get<double>(),
        surrogate.at("surface_nodes").get<int>(), surrogate.at("training_solves").get<int>(),
        surrogate.at("training_seconds").get<double>(), surrogate.value("trained", std::string("here")),
        surrogate.at("queries_per_force").get<int>());
  return md;
}

json surrogate_query_timing(const meshless::Surrogate& surrogate, const Eigen::Vector3d& point,
                            const Eigen::Vector3d& direction, const std::vector<double>& forces, int queries) {
  if (queries < 1) throw std::invalid_argument("surrogate_query_timing: at least one query per force");
  core::PointMatrix u(surrogate.num_surface_nodes(), 3);  // the query's buffer, allocated once
  json rows = json::array();
  std::vector<double> seconds(queries);
  for (double f : forces) {
    meshless::SurrogateResponse r;
    for (int k = 0; k < queries; ++k) {
      const auto q0 = std::chrono::steady_clock::now();
      r = surrogate.query(point, f * direction, &u);
      seconds[k] = std::chrono::duration<double>(std::chrono::steady_clock::now() - q0).count();
    }
    std::nth_element(seconds.begin(), seconds.begin() + queries / 2, seconds.end());
    rows.push_back({{"force_N", f},
                    {"seconds", seconds[queries / 2]},
                    {"contact_displacement_mm", 1e3 * r.contact_displacement.norm()},
                    {"force_in_range", r.force_in_range},
                    {"on_trained_contact", r.on_trained_contact}});
  }
  return rows;
}

ReproducePlan load_reproduce_plan(const std::string& file) {
  const json doc = read_json_file(file);
  core::JsonReader root(file, doc, "");
  ReproducePlan plan;
  plan.file = file;
  root.string("description", std::string());
  const json& table1 =
      root.array("table1", 1, "a non-empty array of {label, config, paper: {enrichment_mm, visibility_mm}}");
  for (std::size_t i = 0; i < table1.size(); ++i) {
    core::JsonReader t(file, table1[i], fmt::format("/table1/{}", i));
    ReproducePlan::Table1Case row;
    row.label = t.string("label");
    if (row.label.empty() || row.label.find_first_of("/\\") != std::string::npos)
      t.fail("label", "a non-empty name without slashes (it names the case's sub-folder)");
    row.config = resolve_case(t, "config", file);
    const core::JsonReader paper = t.object("paper");
    row.paper_enrichment_mm = paper.in_range("enrichment_mm", 0.0, 1e3, true, true);
    row.paper_visibility_mm = paper.in_range("visibility_mm", 0.0, 1e3, true, true);
    paper.finish();
    row.cloud_studies = plan_paths(t, "cloud_studies", file, "sweep folders", "a sweep folder", false);
    row.reference_family =
        plan_paths(t, "reference_family", file, "fem.json files of `tissue verify fem`", "a fem.json file", true);
    t.finish();
    for (const auto& other : plan.table1)
      if (other.label == row.label) t.fail("label", "a label no other Table 1 case has");
    plan.table1.push_back(row);
  }
  const core::JsonReader timing = root.object("timing");
  plan.timing.config = resolve_case(timing, "config", file);
  plan.timing.steps = timing.integer("steps", 1, 100, 1);
  // The timing case is read only when a check below needs it, and then once.
  std::optional<core::Case> timing_case;
  const auto stressed_case = [&]() -> const core::Case& {
    if (!timing_case) timing_case = core::load_case(plan.timing.config);
    return *timing_case;
  };
  if (timing.has("surrogate")) {
    plan.timing.surrogate_config = resolve_case(timing, "surrogate", file);
    const core::Case trained = core::load_case(plan.timing.surrogate_config);
    const core::Case& stressed = stressed_case();
    double nearest = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3d& p : trained.surrogate.contact_points)
      nearest = std::min(nearest, (p - stressed.load.point).norm());
    if (!(nearest <= trained.surrogate.patch_radius))
      timing.fail("surrogate", fmt::format("a case whose /surrogate/contact_points include the timing case's load "
                                           "point (the nearest is {:.3g} mm away; the patch radius is {:.3g} mm)",
                                           1e3 * nearest, 1e3 * trained.surrogate.patch_radius));
  }
  const json& forces = timing.array("forces_N", 1, "a non-empty array of force magnitudes in (0, 100] N");
  for (std::size_t i = 0; i < forces.size(); ++i) {
    if (!forces[i].is_number() || !(forces[i].get<double>() > 0.0) || forces[i].get<double>() > 100.0)
      throw core::CaseError(file, fmt::format("/timing/forces_N/{}", i), "a force magnitude in (0, 100] N");
    plan.timing.forces.push_back(forces[i].get<double>());
  }
  if (timing.has("models")) {
    const json& models = timing.array("models", 1, "a non-empty array of registered model names");
    // The timing case's reference is always timed (it stands first in every row), so the list names the others;
    // refused here, at the plan's path, rather than later at the /compare path of a case the plan rewrote.
    const std::string reference = stressed_case().compare.reference;
    for (std::size_t k = 0; k < models.size(); ++k) {
      const std::string at = fmt::format("models/{}", k);
      if (!models[k].is_string() || !make_model(models[k].get<std::string>()))
        timing.fail(at, fmt::format("a registered model ({})", fmt::join(registered_model_names(), ", ")));
      const std::string name = models[k].get<std::string>();
      if (name == reference)
        timing.fail(at, fmt::format("a model other than the timing case's reference \"{}\" (the reference is always "
                                    "timed)", name));
      if (std::find(plan.timing.models.begin(), plan.timing.models.end(), name) != plan.timing.models.end())
        timing.fail(at, fmt::format("each model once (\"{}\" is listed twice)", name));
      plan.timing.models.push_back(name);
    }
  }
  timing.finish();
  root.finish();
  return plan;
}

bool ReproduceOptions::IsValid(std::string* why) const {
  if (out_dir.empty()) return *why = "--out must not be empty", false;
  if (!table1 && !timing) return *why = "--table1-only and --timing-only exclude each other", false;
  if (jobs < 0) return *why = "--jobs must be >= 0 (0: as many as cores)", false;
  if (jobs != 1 && tissue_binary.empty())
    return *why = "the `tissue` program that runs Table 1's cases side by side is not set (or use --jobs 1)", false;
  return true;
}

namespace {

/// The `tissue compare` options of a Table 1 case, written into `out`'s `label` folder.
CompareOptions table1_compare_options(const ReproducePlan::Table1Case& t, const ReproduceOptions& options,
                                      const core::OutputDirectory& out) {
  CompareOptions compare;
  compare.out_dir = out.file(t.label).string();
  compare.plot = options.plot;
  compare.reference_family = t.reference_family;
  return compare;
}

/// A Table 1 row from the case's compare folder in `out`, with its cloud changes.
json table1_row_of(const ReproducePlan::Table1Case& t, const core::OutputDirectory& out) {
  json row = table1_row(t, read_json_file(out.file(t.label + "/summary.json").string()));
  row["cloud_change"] = row_cloud_change(t, row, false).to_json();
  row["cloud_change_versus_extrapolated"] = row_cloud_change(t, row, true).to_json();
  return row;
}

/// Table 1's rows: each case's `tissue compare`, in this process one after the other, or side by side in child
/// processes (ReproduceOptions::jobs), each kept to its share of the cores.
json table1_rows(const ReproducePlan& plan, const ReproduceOptions& options, const core::OutputDirectory& out,
                 const std::optional<ChildJob>& beside, ProcessOutcome* beside_outcome, Progress* progress) {
  json rows = json::array();
  const int children = options.table1_children(static_cast<int>(plan.table1.size()));
  if (children == 1) {
    for (const auto& t : plan.table1) {
      progress->step(fmt::format("Table 1, {}: tissue compare {}", t.label, t.config));
      if (const int code = run_compare(t.config, table1_compare_options(t, options, out)); code != 0)
        throw std::runtime_error(fmt::format("reproduce: tissue compare {} failed (exit {})", t.config, code));
      rows.push_back(table1_row_of(t, out));
    }
    return rows;
  }
  std::vector<ChildJob> jobs;
  for (const auto& t : plan.table1)
    jobs.push_back({fmt::format("Table 1, {}", t.label),
                    compare_command_line(options.tissue_binary, t.config, table1_compare_options(t, options, out)),
                    out.file(t.label + ".log").string()});
  if (beside) jobs.push_back(*beside);  // last: it starts in the slot the first case to end frees
  SideBySideOptions side;
  side.children = children;
  side.threads_per_child = threads_per_child(children);
  std::vector<ProcessOutcome> outcomes = run_side_by_side(jobs, side, progress);
  if (beside) {
    *beside_outcome = outcomes.back();
    outcomes.pop_back();
    jobs.pop_back();
  }
  std::string failures;
  for (std::size_t i = 0; i < jobs.size(); ++i)
    if (!outcomes[i].ok()) {
      // The staged folder, and the log in it, is removed when this run fails: the log's end is printed here.
      std::cerr << fmt::format("--- the end of {} ---\n{}", jobs[i].log_file, tail_of_file(jobs[i].log_file, 25));
      failures += fmt::format("{}tissue compare {} failed: {}", failures.empty() ? "" : "; ", plan.table1[i].config,
                              child_failure(outcomes[i], jobs[i].log_file));
    }
  if (!failures.empty()) throw std::runtime_error("reproduce: " + failures + " (the end of its log is above)");
  const std::string run = fmt::format("side by side, {} at once with {} thread{} each", children,
                                      side.threads_per_child, side.threads_per_child == 1 ? "" : "s");
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    std::filesystem::remove(jobs[i].log_file);  // it succeeded: its results are in the case's folder
    json row = table1_row_of(plan.table1[i], out);
    row["run"] = run;
    rows.push_back(row);
  }
  return rows;
}

}  // namespace

std::vector<std::string> compare_command_line(const std::string& tissue_binary, const std::string& config,
                                              const CompareOptions& compare) {
  std::vector<std::string> argv{tissue_binary, "compare", config, "--out", compare.out_dir};
  if (!compare.plot) argv.push_back("--no-plot");
  for (const std::string& f : compare.reference_family) {
    argv.push_back("--reference-family");
    argv.push_back(f);
  }
  return argv;
}

int ReproduceOptions::table1_children(int cases) const {
  const int wanted = jobs > 0 ? jobs : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  return std::max(1, std::min(wanted, cases));
}

int run_reproduce(const ReproduceOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("reproduce: " + why);
  const ReproducePlan plan = load_reproduce_plan(options.plan);
  // Every case is read (and rejected) before anything runs.
  std::vector<core::Case> cases;
  for (const auto& t : plan.table1) cases.push_back(core::load_case(t.config));
  const core::Case timing_case = with_timed_models(core::load_case(plan.timing.config), plan.timing.models);
  if (timing_case.load.force.norm() == 0.0)
    throw core::CaseError(plan.timing.config, "/load/force", "a non-zero force (its direction is the timing's)");
  for (double f : plan.timing.forces) case_at_force(timing_case, f, plan.timing.steps);

  for (const auto& c : cases) models_of_case(c);  // an unknown model name is refused before anything runs
  const std::vector<std::unique_ptr<Model>> timed = timed_models(timing_case);
  const int n_forces = static_cast<int>(plan.timing.forces.size());
  const int n_timed = static_cast<int>(timed.size());
  const bool with_surrogate = !plan.timing.surrogate_config.empty();
  // Only the surrogate's queries are timed, not its training; so when Table 1's cases run side by side, `tissue fit`
  // trains it beside them, at one thread in the slot the shorter case frees, and the timing reads its file.
  const bool fit_beside = options.table1 && options.timing && with_surrogate &&
                          options.table1_children(static_cast<int>(plan.table1.size())) > 1;
  Progress progress("reproduce", (options.table1 ? static_cast<int>(plan.table1.size()) : 0) +
                                     (options.timing ? 2 + n_timed * (n_forces + 1) + 2 * with_surrogate : 0) + 1);
  // (With fit_beside the training's step is the fit job's start in Table 1's side-by-side run.)
  core::OutputDirectory out(options.out_dir);
  write_text_file(out.file("plan.json").string(), read_json_file(options.plan).dump(2) + "\n");

  std::optional<ChildJob> fit_job;
  ProcessOutcome fit_outcome;
  const std::string fitted_file = fit_beside ? out.file("surrogate.json").string() : std::string();
  if (fit_beside)
    fit_job = ChildJob{"the timing's surrogate: tissue fit",
                       {options.tissue_binary, "fit", plan.timing.surrogate_config, "--out", fitted_file, "--workers",
                        "1"},
                       out.file("surrogate_fit.log").string()};
  if (options.table1) {
    const json rows = table1_rows(plan, options, out, fit_job, &fit_outcome, &progress);
    write_text_file(out.file("table1.json").string(), json{{"rows", rows}}.dump(2) + "\n");
    const std::string md = table1_md(rows);
    write_text_file(out.file("table1.md").string(), md);
    std::cout << md << "\n";
  }

  if (options.timing) {
    progress.step(fmt::format("timing: geometry of {} (built once for every force)", plan.timing.config));
    const double t0 = progress.elapsed_seconds();
    const core::Geometry g = core::build_geometry(timing_case);
    json timing = {{"config", plan.timing.config},
                   {"steps", plan.timing.steps},
                   {"geometry_seconds", progress.elapsed_seconds() - t0},
                   {"openblas_kernels", core::openblas_core_name()},  // "" when the BLAS is not OpenBLAS
                   {"models", json::array()},
                   {"surrogate", {{"status", "not measured: the plan's /timing has no surrogate case"}}},
                   {"rows", json::array()}};
    std::vector<TimedSeries> series;
    const core::Case first_force = case_at_force(timing_case, plan.timing.forces.front(), plan.timing.steps);
    for (const auto& m : timed) {
      progress.step(fmt::format("timing: {}: set-up for every force on this cloud", m->name()));
      TimedSeries t{m.get(), nullptr, {}};
      try {
        t.series = m->prepare_load_series(first_force, g);
      } catch (const std::exception& e) {  // recorded in every row, like a failed solve
        t.error = std::string("set-up: ") + e.what();
      }
      json entry = {{"name", m->name()}, {"role", m->role()}};
      if (t.series && t.series->setup_seconds() > 0.0) entry["setup_once_seconds"] = t.series->setup_seconds();
      timing["models"].push_back(entry);
      series.push_back(std::move(t));
    }
    for (double f : plan.timing.forces)
      timing["rows"].push_back(time_one_force(case_at_force(timing_case, f, plan.timing.steps), f, series, &progress));
    if (with_surrogate) {
      try {
        if (fit_job && !fit_outcome.ok())  // its log stays in the results for the cause
          throw std::runtime_error(fmt::format("tissue fit {} beside Table 1: {} (the end of surrogate_fit.log: {})",
                                               plan.timing.surrogate_config,
                                               child_failure(fit_outcome, fit_job->log_file),
                                               tail_of_file(fit_job->log_file, 3)));
        timing["surrogate"] =
            time_surrogate(plan.timing.surrogate_config, timing_case, plan.timing.forces, fitted_file, &progress);
        if (fit_job) std::filesystem::remove(fit_job->log_file);  // it succeeded: the file and timing.md tell
      } catch (const std::exception& e) {  // recorded like a failed model run; the rest of the timing stands
        timing["surrogate"] = {{"status", std::string("failed: ") + e.what()}};
      }
    }
    progress.step("timing: tables and timing.png (scripts/plot_timing.py)");
    // The plot script reads timing.json; it is written again with the plot's outcome.
    write_text_file(out.file("timing.json").string(), timing.dump(2) + "\n");
    if (options.plot) {
      plot_timing(out, &timing);
      write_text_file(out.file("timing.json").string(), timing.dump(2) + "\n");
    }
    const std::string md = timing_md(timing);
    write_text_file(out.file("timing.md").string(), md);
    std::cout << md << "\n";
  }
  out.commit();
  progress.done();
  std::cout << fmt::format("wrote {} in {:.0f} s\n", out.destination().string(), progress.elapsed_seconds());
  return 0;
}

}  // namespace experiments
