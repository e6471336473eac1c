#pragma once
#include <CLI/CLI.hpp>

namespace experiments {
/// `tissue solve fem CONFIG --out DIR` (and, later, `tissue solve meshless`).
void add_solve_commands(CLI::App& app);
}  // namespace experiments
