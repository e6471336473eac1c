#pragma once
// The `tissue reproduce` subcommand (experiments/studies/reproduce.hpp).
#include <CLI/CLI.hpp>

namespace experiments {

void add_reproduce_command(CLI::App& app);

}  // namespace experiments
