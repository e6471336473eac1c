#include "experiments/commands/reproduce_command.hpp"

#include "experiments/io/child_process.hpp"
#include "experiments/io/progress.hpp"
#include "experiments/studies/reproduce.hpp"

namespace experiments {

void add_reproduce_command(CLI::App& app) {
  static ReproduceOptions options;
  static bool no_plot = false, table1_only = false, timing_only = false;
  options.plan = std::string(TISSUE_SOURCE_DIR) + "/configs/reproduce.json";
  auto* cmd = app.add_subcommand("reproduce", "Reproduce the paper's Table 1 and the analogue of its Fig. 9");
  cmd->footer("Table 1: the RMSE of the proposed and the baseline meshless cutting models against the FEM reference\n"
              "(§5.4). Fig. 9: the time per deformation result for 8 forces (§5.5): the full meshless solve, the FEM\n"
              "reference and the surrogate's query. Runs on the cases of a plan file and writes table1.md/.json,\n"
              "timing.md/.json, timing.png and each case's compare folder (docs/EXPERIMENTS.md).");
  cmd->add_option("--plan", options.plan, "Plan JSON: the Table 1 cases with the paper's figures, the timing case, the surrogate's case")
      ->capture_default_str();
  cmd->add_option("--out", options.out_dir, "Output folder (written atomically)")->capture_default_str();
  cmd->add_flag("--no-plot", no_plot, "Do not draw radar.png and timing.png");
  cmd->add_flag("--table1-only", table1_only, "Run Table 1 only");
  cmd->add_flag("--timing-only", timing_only, "Run the timing only");
  cmd->add_option("--jobs", options.jobs,
                  "Table 1's cases run at once, each a `tissue compare` child with its share of the cores (0: as many "
                  "as cores; 1: one after the other in this process). The timing always runs alone")
      ->check(CLI::Range(0, 64))
      ->capture_default_str();
  cmd->callback([] {
    options.plot = !no_plot;
    options.table1 = !timing_only;
    options.timing = !table1_only;
    options.tissue_binary = this_program();
    throw CommandResult{run_reproduce(options)};
  });
}

}  // namespace experiments
