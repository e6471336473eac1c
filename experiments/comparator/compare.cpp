#include "experiments/comparator/compare.hpp"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <algorithm>

#include "core/case.hpp"
#include "core/geometry.hpp"
#include "core/output_directory.hpp"
#include "experiments/comparator/mesh_family_error_bar.hpp"
#include "experiments/io/child_process.hpp"
#include "experiments/models/model_registry.hpp"
#include "experiments/io/progress.hpp"
#include "experiments/io/vtu_writer.hpp"

namespace experiments {
namespace {

using nlohmann::json;

/// NaN (no sample left) becomes JSON null.
json number_or_null(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

/// The wall time of each phase of one model's run, from its ModelResult [s].
json phase_seconds(const ModelResult& r) {
  double assembly = 0.0, solve = 0.0;
  int newton = 0;
  for (const auto& s : r.steps) {
    assembly += s.assembly_seconds;
    solve += s.solve_seconds;
    newton += s.iterations;
  }
  return {{"setup_seconds", r.setup_seconds},
          {"assembly_seconds", assembly},
          {"solve_seconds", solve},
          {"total_seconds", r.total_seconds},
          {"newton_iterations", newton}};
}

std::string csv_number(double v) { return fmt::format("{:.9g}", v); }

std::string fixed(const json& v, int digits) {
  return v.is_number() ? fmt::format("{:.{}f}", v.get<double>(), digits) : std::string("–");
}

std::string percent(const json& v) {
  return v.is_number() ? fmt::format("{:.1f} %", 100.0 * v.get<double>()) : std::string("–");
}

}  // namespace

bool CompareOptions::IsValid(std::string* why) const {
  const auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (reference_samples != "solved" && reference_samples != "extrapolated")
    return fail("--reference must be \"solved\" or \"extrapolated\", got \"" + reference_samples + "\"");
  if (out_dir.empty()) return fail("--out is required");
  if (patch_edge_distance && !(*patch_edge_distance >= 0.0)) return fail("--edge-distance must be >= 0 mm");
  if (cut_distance && !(*cut_distance >= 0.0)) return fail("--cut-distance must be >= 0 mm");
  return true;
}

std::string role_kind(const std::string& role) { return role.substr(0, role.find(':')); }

namespace {

bool is_external(const ModelResult& r) { return r.role == "external"; }

/// "–" for a model without timings (an external result), else the phase's seconds.
std::string seconds_or_dash(const json& timings, const char* phase) {
  return timings.is_object() ? fmt::format("{:.1f}", timings[phase].get<double>()) : std::string("–");
}

json cut_effect_summary(const Comparison& c) {
  auto uncut_of = [&](const std::string& name) -> const Eigen::MatrixXd& {
    for (const auto& [model, u] : c.uncut_samples)
      if (model == name) return u;
    throw std::logic_error("compare: no uncut solve of " + name);
  };
  // The FEM's effect from its solved samples: an extrapolated reference has no uncut counterpart.
  const Eigen::MatrixXd fem_cut = c.solved_reference_samples.value_or(c.reference.sample_displacements);
  const Eigen::MatrixXd fem_effect = fem_cut - uncut_of(c.reference_name);
  const double peak = peak_magnitude(fem_effect);
  json models = json::object();
  for (const auto& [name, r] : c.models) {
    if (is_external(r)) continue;  // another program's samples come without an uncut solve
    if (std::none_of(c.uncut_samples.begin(), c.uncut_samples.end(), [&](const auto& u) { return u.first == name; }))
      continue;
    const Eigen::MatrixXd effect = r.sample_displacements - uncut_of(name);
    const double error = rmse(effect, fem_effect);
    models[name] = {{"rmse_mm", error * 1e3},
                    {"rmse_relative_to_fem_peak", peak > 0 ? json(error / peak) : json(nullptr)},
                    {"peak_effect_mm", peak_magnitude(effect) * 1e3}};
  }
  return {{"definition", "each model's cut solve minus its own uncut solve at the samples; RMSE (eq. 34) of that "
                         "effect against the FEM's, relative to the peak of the FEM's effect"},
          {"fem_peak_effect_mm", peak * 1e3},
          {"models", models}};
}

/// The RMS distance [mm] of this run's solved FEM samples from the study's extrapolated ones, whichever stands for
/// the reference; null without extrapolated samples.
json solved_minus_extrapolated_mm(const Comparison& c) {
  if (c.solved_reference_samples) return rmse(*c.solved_reference_samples, c.reference.sample_displacements) * 1e3;
  if (c.error_bar.known && c.error_bar.extrapolated_samples)
    return rmse(c.reference.sample_displacements, *c.error_bar.extrapolated_samples) * 1e3;
  return nullptr;
}

/// With the solved reference and a mesh study that extrapolated it: every model's eq. 34 RMSE against the study's
/// extrapolated samples as well, beside their own (smaller) bar, so that one run says both how far a model is from
/// this reference and how far from the converged FEM (docs/EXPERIMENTS.md, "The extrapolated reference").
json versus_extrapolated_summary(const Comparison& c) {
  const Eigen::MatrixXd& x = *c.error_bar.extrapolated_samples;
  const double peak = peak_magnitude(x);
  json models = json::object();
  for (const auto& [name, r] : c.models) {
    const double error = rmse(r.sample_displacements, x);
    models[name] = {{"rmse_mm", error * 1e3}, {"rmse_relative_to_peak", error / peak}};
  }
  return {{"definition", "each model's RMSE (eq. 34) against the mesh study's extrapolated FEM samples, relative to "
                         "their peak; their bar is the study's finest level's estimated error"},
          {"peak_sample_displacement_mm", peak * 1e3},
          {"error_bar_mm", c.error_bar.extrapolated_rms_mm()},
          {"error_bar_method", c.error_bar.extrapolated_method},
          {"models", models}};
}

}  // namespace

json comparison_summary(const Comparison& c) {
  const Eigen::MatrixXd& u_ref = c.reference.sample_displacements;
  const double peak = peak_magnitude(u_ref);
  const std::vector<bool> keep = c.diagnostics.unflagged_mask();
  json flagged = json::array();
  for (std::size_t i = 0; i < keep.size(); ++i)
    if (!keep[i]) flagged.push_back(i);

  json models = json::object();
  for (const auto& [name, r] : c.models) {
    const double all = rmse(r.sample_displacements, u_ref);
    const double unflagged = rmse(r.sample_displacements, u_ref, keep);
    double max_error = 0.0;
    for (Eigen::Index i = 0; i < u_ref.rows(); ++i)
      max_error = std::max(max_error, (r.sample_displacements.row(i) - u_ref.row(i)).norm());
    json m = {{"rmse_mm", all * 1e3},
              {"rmse_relative_to_peak", all / peak},
              {"rmse_unflagged_mm", number_or_null(unflagged * 1e3)},
              {"rmse_unflagged_relative_to_peak", number_or_null(unflagged / peak)},
              {"n_unflagged", keep.size() - c.diagnostics.num_flagged()},
              {"max_sample_error_mm", max_error * 1e3},
              {"peak_sample_displacement_mm", peak_magnitude(r.sample_displacements) * 1e3},
              {"reference_error_bar_mm", c.error_bar.known ? json(c.error_bar.rms_mm) : json(nullptr)},
              {"timings", is_external(r) ? json(nullptr) : phase_seconds(r)},
              {"details", r.details}};
    m["role"] = is_external(r) ? std::string("external") : r.role;
    models[name] = m;
  }
  json not_solved = json::object();
  for (const auto& n : c.not_solved) not_solved[n.name] = {{"role", n.role}, {"why", n.why}};
  json summary = {
      {"case", c.case_name},
      {"config", c.config},
      {"n_samples", u_ref.rows()},
      {"flag_rules",
       {{"patch_edge_distance_mm", c.rules.patch_edge_distance * 1e3}, {"cut_distance_mm", c.rules.cut_distance * 1e3}}},
      {"flagged_samples", flagged},
      {"geometry_seconds", c.geometry_seconds},
      {"reference",
       {{"model", c.reference_name},
        {"samples", c.solved_reference_samples ? "extrapolated" : "solved"},
        {"solved_minus_extrapolated_rms_mm", solved_minus_extrapolated_mm(c)},
        {"peak_sample_displacement_mm", peak * 1e3},
        {"error_bar", c.error_bar.to_json()},
        {"timings", phase_seconds(c.reference)},
        {"details", c.reference.details}}},
      {"models", models}};
  if (!c.not_solved.empty()) summary["not_solved"] = not_solved;
  if (!c.uncut_samples.empty()) summary["cut_effect"] = cut_effect_summary(c);
  if (!c.solved_reference_samples && c.error_bar.known && c.error_bar.extrapolated_samples)
    summary["versus_extrapolated"] = versus_extrapolated_summary(c);
  // The paper's Table 1 difference: the proposed model against the baseline, when the case has both.
  const auto with_role = [&](const std::string& kind) -> const std::pair<std::string, ModelResult>* {
    for (const auto& m : c.models)
      if (!is_external(m.second) && role_kind(m.second.role) == kind) return &m;
    return nullptr;
  };
  const auto* proposed = with_role("proposed");
  const auto* baseline = with_role("baseline");
  if (proposed && baseline) {
    const auto& [first, a_result] = *proposed;
    const auto& [second, b_result] = *baseline;
    const auto& a = a_result.sample_displacements;
    const auto& b = b_result.sample_displacements;
    summary["difference_mm"] = models[first]["rmse_mm"].get<double>() - models[second]["rmse_mm"].get<double>();
    summary["difference_definition"] =
        fmt::format("RMSE({}) - RMSE({}), the third column of the paper's Table 1", first, second);
    summary["variants_max_sample_difference_mm"] = (a - b).rowwise().norm().maxCoeff() * 1e3;
    if (c.has_cut && (a - b).cwiseAbs().maxCoeff() == 0.0)
      summary["warning"] = fmt::format("the case has a cut, yet {} and {} gave identical sample displacements: the "
                                       "meshless model does not distinguish the two variants",
                                       first, second);
  }
  return summary;
}

std::string comparison_samples_csv(const Comparison& c) {
  std::string csv =
      "sample,model,x_mm,y_mm,z_mm,ux_mm,uy_mm,uz_mm,magnitude_mm,error_to_reference_mm,edge_distance_mm,"
      "cut_distance_mm,on_patch_edge,near_cut,flagged\n";
  const Eigen::MatrixXd& u_ref = c.reference.sample_displacements;
  std::vector<std::pair<std::string, const ModelResult*>> all{{c.reference_name, &c.reference}};
  for (const auto& [name, r] : c.models) all.emplace_back(name, &r);
  for (Eigen::Index i = 0; i < c.sample_points.rows(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    const Eigen::Vector3d x = c.sample_points.row(i).transpose() * 1e3;
    for (const auto& [name, r] : all) {
      const Eigen::Vector3d u = r->sample_displacements.row(i).transpose() * 1e3;
      const std::string error =
          r == &c.reference ? "" : csv_number((r->sample_displacements.row(i) - u_ref.row(i)).norm() * 1e3);
      const auto& cut = c.diagnostics.cut_distance[k];
      // eq. 33: the magnitude is the distance between the deformed and the original position of the sample.
      csv += fmt::format("{},{},{:.6f},{:.6f},{:.6f},{},{},{},{},{},{:.6f},{},{},{},{}\n", i, name, x(0), x(1), x(2),
                         csv_number(u(0)), csv_number(u(1)), csv_number(u(2)), csv_number(u.norm()), error,
                         c.diagnostics.edge_distance[k] * 1e3, cut ? fmt::format("{:.6f}", *cut * 1e3) : "",
                         int(c.diagnostics.on_patch_edge[k]), int(c.diagnostics.near_cut[k]),
                         int(c.diagnostics.flagged(k)));
    }
  }
  return csv;
}

std::string comparison_table_md(const Comparison& c, const json& s) {
  const std::string reference =
      c.solved_reference_samples
          ? fmt::format("the FEM model's samples extrapolated by its mesh study (docs/EXPERIMENTS.md, \"The "
                        "extrapolated reference\"); this run's solved FEM samples differ from them by {:.4f} mm RMS",
                        s["reference"]["solved_minus_extrapolated_rms_mm"].get<double>())
          : fmt::format("the model \"{}\" as solved here ({})", c.reference_name, c.reference.role);
  std::string md = fmt::format("# Comparison: {}\n\nProduced by `tissue compare {}`. Reference: {}. RMSE of eq. 34 "
                               "over the {} samples; the peak reference sample displacement is {:.4f} mm.\n\n",
                               c.case_name, c.config, reference, s["n_samples"].get<int>(),
                               s["reference"]["peak_sample_displacement_mm"].get<double>());
  const json& bar = s["reference"]["error_bar"];
  const std::string bar_text = bar["known"].get<bool>()
                                   ? fmt::format("{:.4f}", bar["rms_mm"].get<double>())
                                   : std::string("unknown");
  md += fmt::format("| model | RMSE [mm] | RMSE / peak | RMSE without flagged [mm] ({} samples) | without flagged / "
                    "peak | reference error bar [mm] | max sample error [mm] | solve time [s] |\n"
                    "|---|---|---|---|---|---|---|---|\n",
                    c.models.empty() ? 0 : s["models"][c.models[0].first]["n_unflagged"].get<int>());
  for (const auto& [name, r] : c.models) {
    const json& m = s["models"][name];
    md += fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} |\n", name, fixed(m["rmse_mm"], 4),
                      percent(m["rmse_relative_to_peak"]), fixed(m["rmse_unflagged_mm"], 4),
                      percent(m["rmse_unflagged_relative_to_peak"]), bar_text, fixed(m["max_sample_error_mm"], 4),
                      seconds_or_dash(m["timings"], "total_seconds"));
  }
  if (s.contains("difference_mm"))
    md += fmt::format("\nDifference ({}): **{:.4f} mm**.\n", s["difference_definition"].get<std::string>(),
                      s["difference_mm"].get<double>());
  if (s.contains("cut_effect")) {
    const json& e = s["cut_effect"];
    md += fmt::format("\n**The cut's own effect** ({}); the FEM's peak effect is {:.4f} mm:\n\n"
                      "| model | cut-effect RMSE [mm] | / FEM peak effect | peak effect [mm] |\n|---|---|---|---|\n",
                      e["definition"].get<std::string>(), e["fem_peak_effect_mm"].get<double>());
    for (const auto& [name, m] : e["models"].items())
      md += fmt::format("| {} | {} | {} | {} |\n", name, fixed(m["rmse_mm"], 4), percent(m["rmse_relative_to_fem_peak"]),
                        fixed(m["peak_effect_mm"], 4));
  }
  md += "\nRoles: ";
  for (std::size_t i = 0; i < c.models.size(); ++i)
    md += fmt::format("{}{} ({})", i ? "; " : "", c.models[i].first,
                      is_external(c.models[i].second) ? std::string("external") : c.models[i].second.role);
  md += ".\n";
  for (const auto& n : c.not_solved)
    md += fmt::format("\n{} ({}): {}{}.\n", n.name, n.role, n.why.rfind("failed", 0) == 0 ? "" : "not solved: ", n.why);
  for (const auto& [name, m] : s["models"].items())
    if (m["details"].contains("solved_as_why"))
      md += fmt::format("\n{}: {}.\n", name, m["details"]["solved_as_why"].get<std::string>());
  for (const auto& [name, m] : s["models"].items())
    if (m.value("role", std::string()) == "external")
      md += fmt::format("\n{}: external, another program's samples read from {} (positions within {:.6f} mm of the "
                        "case's samples; no timings, no cut effect).\n",
                        name, m["details"]["source"].get<std::string>(),
                        m["details"]["largest_position_offset_mm"].get<double>());
  if (s.contains("versus_extrapolated")) {
    const json& v = s["versus_extrapolated"];
    md += fmt::format("\n**Against the converged FEM**: the mesh study's extrapolated samples (peak {:.4f} mm, bar "
                      "{:.4f} mm; this reference is {:.4f} mm RMS from them):\n\n| model | RMSE [mm] | / peak |\n"
                      "|---|---|---|\n",
                      v["peak_sample_displacement_mm"].get<double>(), v["error_bar_mm"].get<double>(),
                      s["reference"]["solved_minus_extrapolated_rms_mm"].get<double>());
    for (const auto& [name, r] : c.models)
      md += fmt::format("| {} | {} | {} |\n", name, fixed(v["models"][name]["rmse_mm"], 4),
                        percent(v["models"][name]["rmse_relative_to_peak"]));
  }
  md += bar["known"].get<bool>()
            ? fmt::format("\nReference error bar: {} ({:.2f} % of the sample displacements; {}).\n",
                          bar_text + " mm", 100.0 * bar["relative"].get<double>(), bar["method"].get<std::string>())
            : fmt::format("\nReference error bar unknown: {}.\n", bar["why_unknown"].get<std::string>());
  if (s.contains("warning")) md += fmt::format("\n**Warning:** {}.\n", s["warning"].get<std::string>());

  md += fmt::format("\n## Samples (eq. 33 magnitudes, mm)\n\nFlagged: within {:.2f} mm of the load-patch edge (e) or "
                    "within {:.2f} mm of the cut (c).\n\n| sample | edge distance | cut distance | flag | {} |",
                    c.rules.patch_edge_distance * 1e3, c.rules.cut_distance * 1e3, c.reference_name);
  std::string rule = "|---|---|---|---|---|";
  for (const auto& [name, r] : c.models) {
    md += fmt::format(" {} | {} error |", name, name);
    rule += "---|---|";
  }
  md += "\n" + rule + "\n";
  for (Eigen::Index i = 0; i < c.sample_points.rows(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    const auto& cut = c.diagnostics.cut_distance[k];
    std::string flag = std::string(c.diagnostics.on_patch_edge[k] ? "e" : "") + (c.diagnostics.near_cut[k] ? "c" : "");
    md += fmt::format("| {} | {:.2f} | {} | {} | {:.4f} |", i, c.diagnostics.edge_distance[k] * 1e3,
                      cut ? fmt::format("{:.2f}", *cut * 1e3) : "–", flag,
                      c.reference.sample_displacements.row(i).norm() * 1e3);
    for (const auto& [name, r] : c.models)
      md += fmt::format(" {:.4f} | {:.4f} |", r.sample_displacements.row(i).norm() * 1e3,
                        (r.sample_displacements.row(i) - c.reference.sample_displacements.row(i)).norm() * 1e3);
    md += "\n";
  }

  md += fmt::format("\n## Wall time of each phase [s]\n\nGeometry and meshes (shared): {:.1f} s.\n\n| phase | {} |",
                    c.geometry_seconds, c.reference_name);
  rule = "|---|---|";
  for (const auto& [name, r] : c.models) {
    md += " " + name + " |";
    rule += "---|";
  }
  md += "\n" + rule + "\n";
  for (const char* phase : {"setup_seconds", "assembly_seconds", "solve_seconds", "total_seconds"}) {
    md += fmt::format("| {} | {:.1f} |", std::string(phase).substr(0, std::string(phase).find('_')),
                      s["reference"]["timings"][phase].get<double>());
    for (const auto& [name, r] : c.models) md += " " + seconds_or_dash(s["models"][name]["timings"], phase) + " |";
    md += "\n";
  }
  return md;
}

std::vector<std::string> compare_row_columns(const std::vector<std::string>& models) {
  std::vector<std::string> columns{"n_samples", "n_flagged", "fem_peak_mm", "fem_error_bar_mm"};
  for (const auto& m : models)
    for (const char* suffix : {"_rmse_mm", "_rmse_relative", "_rmse_unflagged_mm"}) columns.push_back(m + suffix);
  columns.insert(columns.end(), {"difference_mm", "geometry_seconds", "fem_seconds"});
  for (const auto& m : models) columns.push_back(m + "_seconds");
  columns.insert(columns.end(), {"fem_dofs", "meshless_nodes"});
  return columns;
}

std::vector<std::string> compare_row_values(const json& s, const std::vector<std::string>& models) {
  const auto num = [](const json& v) { return v.is_number() ? fmt::format("{:.9g}", v.get<double>()) : std::string(); };
  const auto at = [&](const json& obj, const std::vector<std::string>& path) {
    const json* p = &obj;
    for (const auto& key : path) {
      if (!p->is_object() || !p->contains(key)) return std::string();
      p = &(*p)[key];
    }
    return num(*p);
  };
  // A summary written by another version, or cut short, may lack any key: each missing one is an empty cell.
  static const json no_models = json::object();
  const json& m = s.is_object() && s.contains("models") ? s["models"] : no_models;
  const bool has_flags = s.is_object() && s.contains("flagged_samples") && s["flagged_samples"].is_array();
  std::vector<std::string> values{at(s, {"n_samples"}), has_flags ? std::to_string(s["flagged_samples"].size()) : "",
                                  at(s, {"reference", "peak_sample_displacement_mm"}),
                                  at(s, {"reference", "error_bar", "rms_mm"})};
  for (const auto& name : models)
    for (const char* key : {"rmse_mm", "rmse_relative_to_peak", "rmse_unflagged_mm"}) values.push_back(at(m, {name, key}));
  values.insert(values.end(), {at(s, {"difference_mm"}), at(s, {"geometry_seconds"}),
                               at(s, {"reference", "timings", "total_seconds"})});
  for (const auto& name : models) values.push_back(at(m, {name, "timings", "total_seconds"}));
  values.push_back(at(s, {"reference", "details", "n_dofs"}));
  std::string nodes;  // the node cloud of the first scored model that has one
  for (const auto& name : models)
    if (nodes.empty()) nodes = at(m, {name, "details", "n_nodes"});
  values.push_back(nodes);
  return values;
}

namespace {

/// The reference's error bar from a `tissue verify fem` result, or why it is unknown.
ReferenceErrorBar lookup_error_bar(const std::string& file, const core::Case& c, const Eigen::MatrixXd& fem_samples) {
  ReferenceErrorBar unknown;
  unknown.source = file;
  if (file.empty() || !std::filesystem::exists(file)) {
    unknown.why_unknown = fmt::format("no mesh study: {} does not exist (run `tissue verify fem` on this case, or "
                                      "pass --reference-error FILE)",
                                      file.empty() ? std::string("no file given") : file);
    return unknown;
  }
  std::ifstream in(file);
  const json study = json::parse(in, nullptr, false);
  if (study.is_discarded()) {
    unknown.why_unknown = file + " is not valid JSON";
    return unknown;
  }
  return reference_error_bar(study, file, c.name, c.geometry.mesh_size, fem_samples);
}

/// A model's solve with its progress lines prefixed; `same_as` results already in `solved` are reused.
struct Solver {
  const core::Case& c;
  const core::Geometry& g;
  Progress* progress;
  std::string prefix;

  ModelResult operator()(const Model& m, const std::string& vtu_prefix) const {
    SolveRequest request;
    request.vtu_prefix = vtu_prefix;
    request.on_step = [this](const std::string& line) { progress->step(prefix + line); };
    ModelResult r = m.solve(c, g, request);
    r.role = m.role();
    return r;
  }
};

/// The solves `models` (the reference first) need on case `c`: a model that cannot solve it, or whose result equals
/// an earlier one's (Model::same_as), needs none. The progress counter's lines of those solves.
int progress_lines_of_solves(const std::vector<std::unique_ptr<Model>>& models, const core::Case& c) {
  int lines = 0;
  std::vector<std::string> solved;
  for (const auto& m : models) {
    if (!m->cannot_solve(c).empty()) continue;
    const std::string same = m->same_as(c);
    if (!same.empty() && std::find(solved.begin(), solved.end(), same) != solved.end()) continue;
    lines += m->progress_lines(c);
    solved.push_back(m->name());
  }
  return lines;
}

/// Each model's own uncut solve, for the cut effect: on the uncut body's FEM mesh and the cut body's node cloud
/// without its cut (the same samples, which come from the exact surface). A model whose uncut result equals an
/// earlier one's (the two meshless variants: without a cut they are one model) is solved once.
void solve_uncut(const core::Case& c, const core::Geometry& g, const std::vector<std::unique_ptr<Model>>& models,
                 Progress* progress, Comparison* cmp) {
  core::Case uncut = c;
  uncut.cut.reset();
  core::Geometry uncut_geometry = g;  // the cut body's node cloud, without its cut
  uncut_geometry.cut.reset();
  const bool any_fem = std::any_of(models.begin(), models.end(), [&](const auto& m) {
    return m->needs_fem_mesh() && m->cannot_solve(c).empty();
  });
  progress->step("cut effect: the uncut body's FEM mesh (Gmsh)");
  if (any_fem) {
    core::GeometryOptions fem_only;
    fem_only.build_node_cloud = false;
    core::Geometry g_uncut = core::build_geometry(uncut, fem_only);
    if (g_uncut.sample_points.rows() != g.sample_points.rows() ||
        (g_uncut.sample_points - g.sample_points).cwiseAbs().maxCoeff() > 1e-9)
      throw std::runtime_error("compare: the uncut body's samples differ from the cut body's; the cut effect cannot "
                               "be taken at the same points (run with --no-cut-effect)");
    uncut_geometry.fem_mesh = std::move(g_uncut.fem_mesh);
  }
  const Solver solve{uncut, uncut_geometry, progress, "cut effect: uncut "};
  for (const auto& m : models) {
    if (!m->cannot_solve(c).empty() || !m->cannot_solve(uncut).empty()) continue;
    const std::string same = m->same_as(uncut);
    const auto earlier = std::find_if(cmp->uncut_samples.begin(), cmp->uncut_samples.end(),
                                      [&](const auto& u) { return u.first == same; });
    if (!same.empty() && earlier != cmp->uncut_samples.end()) {
      Eigen::MatrixXd u = earlier->second;
      cmp->uncut_samples.emplace_back(m->name(), std::move(u));
      continue;
    }
    if (std::any_of(cmp->not_solved.begin(), cmp->not_solved.end(), [&](const NotSolved& n) { return n.name == m->name(); }))
      continue;  // its cut solve failed: no cut effect to take
    try {
      cmp->uncut_samples.emplace_back(m->name(), solve(*m, std::string()).sample_displacements);
    } catch (const std::exception& e) {
      if (m.get() == models.front().get()) throw;  // the reference's effect is what every other is scored against
      progress->step(fmt::format("cut effect: uncut {}: FAILED: {}", m->name(), e.what()));
    }
  }
}

/// Replace the solved FEM samples by the study's extrapolated ones, with their bar; refuses, saying why, when the
/// study cannot give them for exactly this reference.
void use_extrapolated_reference(const std::string& file, Comparison* cmp) {
  ReferenceErrorBar& bar = cmp->error_bar;
  if (!bar.known || !bar.extrapolated_samples)
    throw std::runtime_error(fmt::format(
        "--reference extrapolated needs a mesh study of exactly this reference with extrapolated samples in {}: {}; "
        "run `tissue verify fem --config {}` (its sizes ending at or below this case's mesh size) and pass its "
        "fem.json with --reference-error (or studies of another mesh family with --reference-family), or compare "
        "with the solved reference",
        file, bar.known ? "the study holds no extrapolated samples (written by verify fem since the elastic support)"
                        : bar.why_unknown,
        cmp->config));
  cmp->solved_reference_samples = cmp->reference.sample_displacements;
  cmp->reference.sample_displacements = *bar.extrapolated_samples;
  cmp->reference.model = "fem (extrapolated)";
  bar.relative = bar.extrapolated_relative;
  bar.rms_mm = bar.extrapolated_rms_mm();
  bar.method = bar.extrapolated_method;
}

void write_plot(const core::OutputDirectory& out, const std::string& case_name, json* summary) {
  const std::string script = std::string(TISSUE_SOURCE_DIR) + "/scripts/plot_radar.py";
  const std::string log = out.file("plot.log").string();
  const ProcessOutcome p = run_process({plot_python(), script, out.file("samples.csv").string(),
                                        out.file("radar.png").string(), "--title", case_name},
                                       log);
  if (p.ok()) {
    std::filesystem::remove(log);
    (*summary)["radar_png"] = "radar.png";
    return;
  }
  // The numbers are the result; a missing plot is reported, not fatal.
  std::filesystem::remove(out.file("radar.png"));
  std::ifstream in(log);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  const std::string why = p.error + (last.empty() ? "" : ": " + last);
  std::cerr << "warning: radar.png not written (" << why << "); see plot.log. It needs Debian's python3-matplotlib "
               "(scripts/install_dependencies.sh)\n";
  (*summary)["radar_png"] = nullptr;
  (*summary)["plot_error"] = why;
}

}  // namespace

int run_compare(const std::string& config, const CompareOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("compare: " + why);
  const core::Case c = core::load_case(config);
  const std::vector<std::unique_ptr<Model>> models = models_of_case(c);  // the reference first
  check_external_names(options.externals, registered_model_names());  // every model of the case is registered
  if (const std::string no = models.front()->cannot_solve(c); !no.empty())
    throw core::CaseError(config, "/compare/reference",
                          fmt::format("a reference that can solve this case; \"{}\" cannot: {}", c.compare.reference, no));
  // Other programs' files are read and checked now, their positions once the geometry has the samples: a wrong
  // file is refused in seconds, never after the solves.
  std::vector<ExternalSamples> external_samples;
  for (const auto& e : options.externals) external_samples.push_back(read_external_samples(e.file, c.samples.count));
  // Another mesh family's studies are read and checked now too: a wrong study costs seconds, not the solves.
  std::optional<MeshFamily> family;
  if (!options.reference_family.empty()) family = read_mesh_family(options.reference_family, c);
  if (options.reference_samples == "extrapolated" && !family &&
      !std::filesystem::exists(options.reference_error_file))
    throw std::runtime_error(fmt::format("--reference extrapolated needs the mesh study given by --reference-error, "
                                         "but {} does not exist; run `tissue verify fem --config {}` first",
                                         options.reference_error_file, config));
  core::Case uncut = c;
  uncut.cut.reset();
  const int uncut_lines = c.cut && options.cut_effect ? 1 + progress_lines_of_solves(models, uncut) : 0;
  Progress progress("compare " + c.name, 1 + progress_lines_of_solves(models, c) + uncut_lines + 2);
  core::OutputDirectory out(options.out_dir);  // staged: nothing is left behind if anything below fails

  core::GeometryOptions meshes;
  meshes.build_fem_mesh = std::any_of(models.begin(), models.end(), [](const auto& m) { return m->needs_fem_mesh(); });
  meshes.build_node_cloud =
      std::any_of(models.begin(), models.end(), [](const auto& m) { return m->needs_node_cloud(); });
  progress.step(fmt::format("building the geometry{}{} (Gmsh)", meshes.build_fem_mesh ? ", the FEM mesh" : "",
                            meshes.build_node_cloud ? ", the node cloud" : ""));
  const double t0 = progress.elapsed_seconds();
  const core::Geometry g = core::build_geometry(c, meshes);  // one geometry: the same samples for all
  Comparison cmp;
  cmp.geometry_seconds = progress.elapsed_seconds() - t0;
  cmp.case_name = c.name;
  cmp.config = config;
  cmp.sample_points = g.sample_points;
  if (family) check_family_sample_points(*family, g.sample_points);
  cmp.has_cut = g.cut.has_value();
  cmp.reference_name = models.front()->name();
  std::vector<std::pair<std::string, ModelResult>> externals;
  for (std::size_t i = 0; i < options.externals.size(); ++i)
    externals.emplace_back(options.externals[i].name,
                           external_model_result(external_samples[i], options.externals[i].name, g.sample_points));

  const Solver solve{c, g, &progress, ""};
  const auto vtu_prefix = [&](const std::string& name) {
    return c.output.vtu ? out.file(name + "/displacement").string() : std::string();
  };
  cmp.reference = solve(*models.front(), vtu_prefix(cmp.reference_name));
  for (std::size_t k = 1; k < models.size(); ++k) {
    const Model& m = *models[k];
    if (const std::string no = m.cannot_solve(c); !no.empty()) {
      cmp.not_solved.push_back({m.name(), m.role(), no});
      continue;
    }
    const std::string same = m.same_as(c);
    const auto earlier = std::find_if(cmp.models.begin(), cmp.models.end(), [&](const auto& e) { return e.first == same; });
    if (same.empty() || earlier == cmp.models.end()) {
      // A scored model that fails is reported with its error and the comparison goes on: the other models' figures
      // stand (the reference's failure ends the comparison, since nothing can be scored without it).
      try {
        cmp.models.emplace_back(m.name(), solve(m, vtu_prefix(m.name())));
      } catch (const std::exception& e) {
        progress.step(fmt::format("{}: FAILED: {}", m.name(), e.what()));
        cmp.not_solved.push_back({m.name(), m.role(), std::string("failed: ") + e.what()});
        std::filesystem::remove_all(out.file(m.name()));
      }
      continue;
    }
    // The same model as an earlier one on this case, bit for bit: its result (and its VTU) stand for this one too.
    ModelResult r = earlier->second;
    r.role = m.role();
    r.details["solved_as"] = same;
    r.details["solved_as_why"] = fmt::format("on this case {} and {} are the same model; it was solved once and its "
                                             "timings are those of that solve", same, m.name());
    if (std::filesystem::is_directory(out.file(same))) {
      std::filesystem::create_directories(out.file(m.name()));
      for (const auto& f : std::filesystem::directory_iterator(out.file(same)))
        std::filesystem::copy_file(f.path(), out.file(m.name()) / f.path().filename());
    }
    cmp.models.emplace_back(m.name(), std::move(r));
  }

  for (auto& e : externals) cmp.models.push_back(std::move(e));
  if (cmp.has_cut && options.cut_effect) solve_uncut(c, g, models, &progress, &cmp);

  progress.step("comparing at the samples and writing the results");
  cmp.rules.patch_edge_distance =
      options.patch_edge_distance.value_or(core::kPatchEdgeBandPerLoadRadius * c.load.radius);
  cmp.rules.cut_distance = options.cut_distance.value_or(c.meshless.node_spacing);
  cmp.diagnostics = diagnose_samples(g.sample_points, g.load_centre, c.load.radius, g.cut, cmp.rules);
  cmp.error_bar = family ? error_bar_against_family(*family, g.sample_points, cmp.reference.sample_displacements)
                         : lookup_error_bar(options.reference_error_file, c, cmp.reference.sample_displacements);
  if (options.reference_samples == "extrapolated")
    use_extrapolated_reference(family ? cmp.error_bar.source : options.reference_error_file, &cmp);
  json summary = comparison_summary(cmp);

  write_text_file(out.file("case.json").string(), c.document.dump(2) + "\n");
  write_text_file(out.file("samples.csv").string(), comparison_samples_csv(cmp));
  write_timings_json(out.file(cmp.reference_name + "/timings.json").string(), cmp.reference);
  for (const auto& [name, r] : cmp.models)
    if (!is_external(r)) write_timings_json(out.file(name + "/timings.json").string(), r);
  Eigen::MatrixXd flagged(cmp.sample_points.rows(), 1);
  for (Eigen::Index i = 0; i < flagged.rows(); ++i) flagged(i, 0) = cmp.diagnostics.flagged(static_cast<std::size_t>(i));
  std::vector<VtuField> fields{{cmp.reference_name, cmp.reference.sample_displacements}, {"flagged", flagged}};
  for (const auto& [name, r] : cmp.models) fields.push_back({name, r.sample_displacements});
  write_point_vtu(out.file("samples.vtu").string(), cmp.sample_points, fields);

  progress.step("radar diagram (scripts/plot_radar.py)");
  if (options.plot)
    write_plot(out, c.name, &summary);
  else
    summary["radar_png"] = nullptr;
  write_text_file(out.file("summary.json").string(), summary.dump(2) + "\n");
  const std::string md = comparison_table_md(cmp, summary);
  write_text_file(out.file("table.md").string(), md);
  out.commit();
  progress.done();
  if (summary.contains("warning")) std::cerr << "warning: " << summary["warning"].get<std::string>() << "\n";
  std::cout << md << fmt::format("\nwrote {}\n", out.destination().string());
  return 0;
}

}  // namespace experiments
