#include "experiments/commands/compare_command.hpp"

#include <fmt/format.h>

#include <iostream>

#include "experiments/comparator/compare.hpp"
#include "experiments/comparator/mesh_family_error_bar.hpp"
#include "experiments/models/external/external_result.hpp"
#include "experiments/io/progress.hpp"
#include "experiments/models/model_registry.hpp"

namespace experiments {

void add_compare_command(CLI::App& app) {
  static std::string config;
  static CompareOptions options;
  static double edge_mm = -1.0, cut_mm = -1.0;
  static bool no_plot = false;
  auto* cmd = app.add_subcommand("compare", "Score the case's models and external results against its reference");
  cmd->footer(
      "Runs the case's /compare models (default: the FEM reference and both meshless variants, enrichment = proposed,\n"
      "visibility = baseline; registered: " + fmt::format("{}", fmt::join(registered_model_names(), ", ")) + ") on one case,\n"
      "reads the --external results of other programs (checked before any solve) and compares them all at the same\n"
      "samples (eqs. 33-34). Writes case.json, samples.csv, summary.json (the eq. 34 RMSE with and without flagged\n"
      "samples, the reference's error bar, phase times), table.md, radar.png and VTU files (docs/EXPERIMENTS.md).");
  cmd->add_option("CONFIG", config, "Load-case JSON file (schema: docs/CONFIG.md)")->required();
  cmd->add_option("--out", options.out_dir, "Output folder (written atomically)")->required();
  cmd->add_option("--edge-distance", edge_mm,
                  "Flag samples closer than this to the load-patch circle [mm] (default: load radius / 4)");
  cmd->add_option("--cut-distance", cut_mm,
                  "Flag samples closer than this to the cut [mm] (default: meshless.node_spacing)");
  cmd->add_option("--reference-error", options.reference_error_file,
                  "`tissue verify fem` result (fem.json) holding a mesh study of this exact reference; the error "
                  "bar is reported as unknown otherwise")
      ->capture_default_str();
  cmd->add_option("--reference-family", options.reference_family,
                  "A `tissue verify fem` result (fem.json) of this case's problem in another mesh family (its case may "
                  "differ only in the discretisation: /geometry/mesh_size, /geometry/refinement, /fem, /meshless, ...); "
                  "repeatable: studies beside one another are averaged level by level. When given, the error bar is "
                  "measured against the family's finest level instead of read from --reference-error (docs/EXPERIMENTS.md)")
      ->type_name("FILE")
      ->allow_extra_args(false);
  cmd->add_option("--reference", options.reference_samples,
                  "Which samples stand for the reference: the FEM as solved here, or the Richardson-extrapolated "
                  "samples of the --reference-error study (which must have solved exactly this reference) or of the "
                  "--reference-family")
      ->check(CLI::IsMember({"solved", "extrapolated"}))
      ->capture_default_str();
  cmd->add_flag("--no-plot", no_plot, "Do not run scripts/plot_radar.py (no radar.png)");
  static bool no_cut_effect = false;
  cmd->add_flag("--no-cut-effect", no_cut_effect,
                "Cut cases: do not solve each model without the cut (no cut-effect columns; two solves fewer)");
  static std::vector<std::string> externals;
  cmd->add_option("--external", externals,
                  "Another program's sample displacements, scored as model NAME (repeatable); FILE has the columns of "
                  "samples.csv, in mm (docs/EXPERIMENTS.md, \"Scoring another program\")")
      ->type_name("NAME=FILE")
      ->allow_extra_args(false);
  cmd->callback([] {
    if (edge_mm >= 0.0) options.patch_edge_distance = edge_mm * 1e-3;
    if (cut_mm >= 0.0) options.cut_distance = cut_mm * 1e-3;
    options.plot = !no_plot;
    options.cut_effect = !no_cut_effect;
    try {
      for (const auto& e : externals) options.externals.push_back(parse_external_spec(e));
      throw CommandResult{run_compare(config, options)};
    } catch (const ExternalResultError& e) {  // a bad input file, like a bad case: exit 2, nothing written
      std::cerr << "error: " << e.what() << "\n";
      throw CommandResult{2};
    } catch (const MeshFamilyError& e) {  // the same for a --reference-family study
      std::cerr << "error: " << e.what() << "\n";
      throw CommandResult{2};
    }
  });
}

}  // namespace experiments
