#pragma once
#include <CLI/CLI.hpp>

namespace experiments {
/// `tissue case check` and `tissue case mesh`.
void add_case_commands(CLI::App& app);
}  // namespace experiments
