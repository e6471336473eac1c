#pragma once
#include <CLI/CLI.hpp>

namespace experiments {

/// `tissue sweep SWEEP.json [--workers N] [--out DIR] [--dry-run]` (sweep.hpp).
void add_sweep_command(CLI::App& app);

}  // namespace experiments
