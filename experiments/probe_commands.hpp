#pragma once
#include <CLI/CLI.hpp>

namespace experiments {
/// `tissue probe SURROGATE`: the haptic probe mode, interactive (stdin) or replaying a device trace at a
/// fixed rate with deadlines (docs/SURROGATE.md §6).
void add_probe_commands(CLI::App& app);
}  // namespace experiments
