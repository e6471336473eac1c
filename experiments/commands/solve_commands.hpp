#pragma once
#include <CLI/CLI.hpp>

namespace experiments {
/// `tissue solve fem|meshless CONFIG --out DIR` and `tissue cut CONFIG --out DIR` (progressive incision).
void add_solve_commands(CLI::App& app);
}  // namespace experiments
