#include "experiments/compare.hpp"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>

#include "core/case.hpp"
#include "core/geometry.hpp"
#include "core/output_directory.hpp"
#include "experiments/compare_subprocess.hpp"
#include "experiments/meshless_runs.hpp"
#include "experiments/progress.hpp"
#include "experiments/vtu_writer.hpp"
#include "reference_fem/fem_model.hpp"

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

const std::vector<MeshlessVariant>& meshless_variants() {
  static const std::vector<MeshlessVariant> variants{
      {"enrichment", "the proposed model: MLS weights enriched across the cut (eqs. 29-32)"},
      {"visibility", "the baseline: the visibility criterion across the cut"}};
  return variants;
}

std::vector<std::string> builtin_model_names() {
  std::vector<std::string> names{"fem"};
  for (const auto& v : meshless_variants()) names.push_back(v.name);
  return names;
}

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
  const Eigen::MatrixXd fem_effect = fem_cut - uncut_of("fem");
  const double peak = peak_magnitude(fem_effect);
  json models = json::object();
  for (const auto& [name, r] : c.models) {
    if (is_external(r)) continue;  // another program's samples come without an uncut solve
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
    for (const auto& v : meshless_variants())
      if (v.name == name) m["role"] = v.role;
    if (is_external(r)) m["role"] = "external";
    models[name] = m;
  }
  json summary = {
      {"case", c.case_name},
      {"config", c.config},
      {"n_samples", u_ref.rows()},
      {"flag_rules",
       {{"patch_edge_distance_mm", c.rules.patch_edge_distance * 1e3}, {"cut_distance_mm", c.rules.cut_distance * 1e3}}},
      {"flagged_samples", flagged},
      {"geometry_seconds", c.geometry_seconds},
      {"reference",
       {{"model", "fem"},
        {"samples", c.solved_reference_samples ? "extrapolated" : "solved"},
        {"solved_minus_extrapolated_rms_mm", c.solved_reference_samples
                                                 ? json(rmse(*c.solved_reference_samples, u_ref) * 1e3)
                                                 : json(nullptr)},
        {"peak_sample_displacement_mm", peak * 1e3},
        {"error_bar", c.error_bar.to_json()},
        {"timings", phase_seconds(c.reference)},
        {"details", c.reference.details}}},
      {"models", models}};
  if (!c.uncut_samples.empty()) summary["cut_effect"] = cut_effect_summary(c);
  std::vector<const std::pair<std::string, ModelResult>*> variants;  // the meshless variants: no external result
  for (const auto& m : c.models)
    if (!is_external(m.second)) variants.push_back(&m);
  if (variants.size() == 2) {
    const auto& [first, a_result] = *variants[0];
    const auto& [second, b_result] = *variants[1];
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
  std::vector<std::pair<std::string, const ModelResult*>> all{{"fem", &c.reference}};
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
          : std::string("the FEM model as solved here (docs/FEM_REFERENCE.md)");
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
  for (const auto& [name, m] : s["models"].items())
    if (m["details"].contains("solved_as_why"))
      md += fmt::format("\n{}: {}.\n", name, m["details"]["solved_as_why"].get<std::string>());
  for (const auto& [name, m] : s["models"].items())
    if (m.value("role", std::string()) == "external")
      md += fmt::format("\n{}: external, another program's samples read from {} (positions within {:.6f} mm of the "
                        "case's samples; no timings, no cut effect).\n",
                        name, m["details"]["source"].get<std::string>(),
                        m["details"]["largest_position_offset_mm"].get<double>());
  md += bar["known"].get<bool>()
            ? fmt::format("\nReference error bar: {} ({:.2f} % of the sample displacements; {}).\n",
                          bar_text + " mm", 100.0 * bar["relative"].get<double>(), bar["method"].get<std::string>())
            : fmt::format("\nReference error bar unknown: {}.\n", bar["why_unknown"].get<std::string>());
  if (s.contains("warning")) md += fmt::format("\n**Warning:** {}.\n", s["warning"].get<std::string>());

  md += fmt::format("\n## Samples (eq. 33 magnitudes, mm)\n\nFlagged: within {:.2f} mm of the load-patch edge (e) or "
                    "within {:.2f} mm of the cut (c).\n\n| sample | edge distance | cut distance | flag | fem |",
                    c.rules.patch_edge_distance * 1e3, c.rules.cut_distance * 1e3);
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

  md += fmt::format("\n## Wall time of each phase [s]\n\nGeometry and both meshes (shared): {:.1f} s.\n\n| phase | fem |",
                    c.geometry_seconds);
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

const std::vector<std::string>& compare_row_columns() {
  static const std::vector<std::string> columns{
      "n_samples",          "n_flagged",          "fem_peak_mm",
      "fem_error_bar_mm",   "enrichment_rmse_mm", "enrichment_rmse_relative",
      "enrichment_rmse_unflagged_mm",             "visibility_rmse_mm",
      "visibility_rmse_relative",                 "visibility_rmse_unflagged_mm",
      "difference_mm",      "geometry_seconds",   "fem_seconds",
      "enrichment_seconds", "visibility_seconds", "fem_dofs",
      "meshless_nodes"};
  return columns;
}

std::vector<std::string> compare_row_values(const json& s) {
  const auto num = [](const json& v) { return v.is_number() ? fmt::format("{:.9g}", v.get<double>()) : std::string(); };
  const auto at = [&](const json& obj, const std::vector<std::string>& path) {
    const json* p = &obj;
    for (const auto& key : path) {
      if (!p->is_object() || !p->contains(key)) return std::string();
      p = &(*p)[key];
    }
    return num(*p);
  };
  const json& m = s["models"];
  return {at(s, {"n_samples"}),
          std::to_string(s["flagged_samples"].size()),
          at(s, {"reference", "peak_sample_displacement_mm"}),
          at(s, {"reference", "error_bar", "rms_mm"}),
          at(m, {"enrichment", "rmse_mm"}),
          at(m, {"enrichment", "rmse_relative_to_peak"}),
          at(m, {"enrichment", "rmse_unflagged_mm"}),
          at(m, {"visibility", "rmse_mm"}),
          at(m, {"visibility", "rmse_relative_to_peak"}),
          at(m, {"visibility", "rmse_unflagged_mm"}),
          at(s, {"difference_mm"}),
          at(s, {"geometry_seconds"}),
          at(s, {"reference", "timings", "total_seconds"}),
          at(m, {"enrichment", "timings", "total_seconds"}),
          at(m, {"visibility", "timings", "total_seconds"}),
          at(s, {"reference", "details", "n_dofs"}),
          at(m, {"enrichment", "details", "n_nodes"})};
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

/// Each model's own uncut solve, for the cut effect: the FEM on the uncut body's mesh (the same samples, which come
/// from the exact surface), and the meshless model once on the same node cloud with no cut (without a cut its two
/// variants are one model).
void solve_uncut(const core::Case& c, const core::Geometry& g, Progress* progress, Comparison* cmp) {
  core::Case uncut = c;
  uncut.cut.reset();
  progress->step("cut effect: the uncut body's FEM mesh (Gmsh)");
  const core::Geometry g_uncut = core::build_geometry(uncut);
  if (g_uncut.sample_points.rows() != g.sample_points.rows() ||
      (g_uncut.sample_points - g.sample_points).cwiseAbs().maxCoeff() > 1e-9)
    throw std::runtime_error("compare: the uncut body's samples differ from the cut body's; the cut effect cannot be "
                             "taken at the same points (run with --no-cut-effect)");
  const int steps = c.time.steps;
  reference_fem::FemRunOptions fem_options;
  fem_options.on_step = [&](const reference_fem::StepReport& s) {
    progress->step(fmt::format("cut effect: uncut FEM step {}/{}", s.step, steps));
  };
  cmp->uncut_samples.emplace_back("fem", reference_fem::run_case(uncut, g_uncut, fem_options).sample_displacements);
  core::Geometry same_cloud = g;  // the cut body's node cloud, without its cut
  same_cloud.cut.reset();
  const ModelResult meshless = solve_meshless(uncut, same_cloud, std::string(), [&](const std::string& line) {
    progress->step("cut effect: uncut meshless: " + line);
  });
  for (const auto& v : meshless_variants()) cmp->uncut_samples.emplace_back(v.name, meshless.sample_displacements);
}

/// Replace the solved FEM samples by the study's extrapolated ones, with their bar; refuses, saying why, when the
/// study cannot give them for exactly this reference.
void use_extrapolated_reference(const std::string& file, Comparison* cmp) {
  ReferenceErrorBar& bar = cmp->error_bar;
  if (!bar.known || !bar.extrapolated_samples)
    throw std::runtime_error(fmt::format(
        "--reference extrapolated needs a mesh study of exactly this reference with extrapolated samples in {}: {}; "
        "run `tissue verify fem --config {}` (its sizes ending at or below this case's mesh size) and pass its "
        "fem.json with --reference-error, or compare with the solved reference",
        file, bar.known ? "the study holds no extrapolated samples (written by verify fem since the elastic support)"
                        : bar.why_unknown,
        cmp->config));
  cmp->solved_reference_samples = cmp->reference.sample_displacements;
  cmp->reference.sample_displacements = *bar.extrapolated_samples;
  cmp->reference.model = "fem (extrapolated)";
  const Eigen::MatrixXd& x = *bar.extrapolated_samples;
  bar.relative = bar.extrapolated_relative;
  bar.rms_mm = bar.relative * x.norm() * 1e3 / std::sqrt(static_cast<double>(x.rows()));
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
  check_external_names(options.externals, builtin_model_names());
  const core::Case c = core::load_case(config);
  // Other programs' files are read and checked now, their positions once the geometry has the samples: a wrong
  // file is refused in seconds, never after the solves.
  std::vector<ExternalSamples> external_samples;
  for (const auto& e : options.externals) external_samples.push_back(read_external_samples(e.file, c.samples.count));
  if (options.reference_samples == "extrapolated" && !std::filesystem::exists(options.reference_error_file))
    throw std::runtime_error(fmt::format("--reference extrapolated needs the mesh study given by --reference-error, "
                                         "but {} does not exist; run `tissue verify fem --config {}` first",
                                         options.reference_error_file, config));
  const int steps = c.time.steps;
  // Without a cut the two meshless variants are one model (no weight is modified), so it is solved once.
  const int meshless_solves = c.cut ? static_cast<int>(meshless_variants().size()) : 1;
  const int uncut_steps = c.cut && options.cut_effect ? 1 + 2 * (1 + steps) : 0;  // solve_uncut's progress lines
  Progress progress("compare " + c.name, 1 + (1 + meshless_solves) * (1 + steps) + uncut_steps + 2);
  core::OutputDirectory out(options.out_dir);  // staged: nothing is left behind if anything below fails

  progress.step("building the geometry, the FEM mesh and the node cloud (Gmsh)");
  const double t0 = progress.elapsed_seconds();
  const core::Geometry g = core::build_geometry(c);  // one geometry, both meshes: the same samples for all
  Comparison cmp;
  cmp.geometry_seconds = progress.elapsed_seconds() - t0;
  cmp.case_name = c.name;
  cmp.config = config;
  cmp.sample_points = g.sample_points;
  cmp.has_cut = g.cut.has_value();
  std::vector<std::pair<std::string, ModelResult>> externals;
  for (std::size_t i = 0; i < options.externals.size(); ++i)
    externals.emplace_back(options.externals[i].name,
                           external_model_result(external_samples[i], options.externals[i].name, g.sample_points));

  progress.step(fmt::format("FEM reference: deal.II set-up ({} tets, degree {})", g.fem_mesh.num_tets(), c.fem.degree));
  reference_fem::FemRunOptions fem_options;
  if (c.output.vtu) fem_options.vtu_prefix = out.file("fem/displacement").string();
  fem_options.on_step = [&](const reference_fem::StepReport& s) {
    progress.step(fmt::format("FEM step {}/{} t = {:.3f} s: {} Newton iterations, residual {:.2e}", s.step, steps,
                              s.time, s.newton_iterations, s.residuals.back()));
  };
  cmp.reference = fem_model_result(c, g, reference_fem::run_case(c, g, fem_options), 0.0);
  cmp.reference.details["geometry_seconds"] = nullptr;  // shared by the three models: summary.json/geometry_seconds

  for (const auto& variant : meshless_variants()) {
    if (!cmp.has_cut && !cmp.models.empty()) {
      // The same model as the first variant, bit for bit: its result (and its VTU) stand for this one too.
      const std::string& solved = cmp.models.front().first;
      ModelResult r = cmp.models.front().second;
      r.model = "meshless (" + variant.name + ")";
      r.details["solved_as"] = solved;
      r.details["solved_as_why"] = fmt::format("the case has no cut, so {} and {} are the same model; it was solved "
                                               "once and its timings are those of that solve", solved, variant.name);
      if (std::filesystem::is_directory(out.file(solved))) {
        std::filesystem::create_directories(out.file(variant.name));
        for (const auto& f : std::filesystem::directory_iterator(out.file(solved)))
          std::filesystem::copy_file(f.path(), out.file(variant.name) / f.path().filename());
      }
      cmp.models.emplace_back(variant.name, std::move(r));
      continue;
    }
    core::Case variant_case = c;
    variant_case.meshless.enrichment = variant.name;
    ModelResult r = solve_meshless(variant_case, g,
                                   c.output.vtu ? out.file(variant.name + "/displacement").string() : std::string(),
                                   [&](const std::string& line) { progress.step(variant.name + ": " + line); });
    r.model = "meshless (" + variant.name + ")";
    cmp.models.emplace_back(variant.name, std::move(r));
  }

  for (auto& e : externals) cmp.models.push_back(std::move(e));
  if (cmp.has_cut && options.cut_effect) solve_uncut(c, g, &progress, &cmp);

  progress.step("comparing at the samples and writing the results");
  cmp.rules.patch_edge_distance =
      options.patch_edge_distance.value_or(core::kPatchEdgeBandPerLoadRadius * c.load.radius);
  cmp.rules.cut_distance = options.cut_distance.value_or(c.meshless.node_spacing);
  cmp.diagnostics = diagnose_samples(g.sample_points, g.load_centre, c.load.radius, g.cut, cmp.rules);
  cmp.error_bar = lookup_error_bar(options.reference_error_file, c, cmp.reference.sample_displacements);
  if (options.reference_samples == "extrapolated") use_extrapolated_reference(options.reference_error_file, &cmp);
  json summary = comparison_summary(cmp);

  write_text_file(out.file("case.json").string(), c.document.dump(2) + "\n");
  write_text_file(out.file("samples.csv").string(), comparison_samples_csv(cmp));
  write_timings_json(out.file("fem/timings.json").string(), cmp.reference);
  for (const auto& [name, r] : cmp.models)
    if (!is_external(r)) write_timings_json(out.file(name + "/timings.json").string(), r);
  Eigen::MatrixXd flagged(cmp.sample_points.rows(), 1);
  for (Eigen::Index i = 0; i < flagged.rows(); ++i) flagged(i, 0) = cmp.diagnostics.flagged(static_cast<std::size_t>(i));
  std::vector<VtuField> fields{{"fem", cmp.reference.sample_displacements}, {"flagged", flagged}};
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
