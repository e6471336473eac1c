#pragma once
#include <CLI/CLI.hpp>

namespace experiments {
/// `tissue verify fem` (and, later, `tissue verify meshless`).
void add_verify_commands(CLI::App& app);
}  // namespace experiments
