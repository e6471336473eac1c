#include "experiments/commands/sweep_command.hpp"

#include <filesystem>
#include <stdexcept>

#include "experiments/io/child_process.hpp"
#include "experiments/io/progress.hpp"
#include "experiments/studies/sweep.hpp"

namespace experiments {

void add_sweep_command(CLI::App& app) {
  static std::string sweep_file;
  static SweepOptions options;
  static bool dry_run = false, no_retry = false, no_plot = false;
  auto* cmd = app.add_subcommand("sweep", "Run `tissue compare` over a grid of case parameters (resumable)");
  cmd->footer("The grid is the Cartesian product of case parameters (JSON pointers with lists of values). One row per\n"
              "run is appended to OUT/runs.csv; the current view is in OUT/summary.{csv,md} and OUT/sweep.png\n"
              "(docs/EXPERIMENTS.md).");
  cmd->add_option("SWEEP", sweep_file, "Sweep file (schema: docs/EXPERIMENTS.md; examples in configs/sweeps/)")
      ->required();
  cmd->add_option("--out", options.out_dir, "Sweep folder (default: results/sweeps/<name>)");
  cmd->add_option("--workers", options.workers,
                  "Runs at once, each a child process (default: the sweep file's `workers`, else 1; every run "
                  "already uses both cores of a 2-core machine)");
  cmd->add_flag("--dry-run", dry_run, "Validate every generated case and list the runs; run nothing");
  cmd->add_flag("--no-retry-failed", no_retry, "Skip runs whose last row says failed (default: run them again)");
  cmd->add_flag("--no-plot", no_plot, "Do not draw sweep.png");
  cmd->callback([] {
    options.retry_failed = !no_retry;
    options.plot = !no_plot;
    // Each run is a child of this very program.
    const std::string self = this_program();
    throw CommandResult{run_sweep_command(sweep_file, options, dry_run, self)};
  });
}

}  // namespace experiments
