#pragma once
#include <CLI/CLI.hpp>

namespace experiments {
/// `tissue probe SURROGATE`: the haptic probe mode, interactive (stdin) or replaying a device trace at a
/// fixed rate with deadlines on a real-time thread (experiments/studies/realtime_loop.hpp, docs/SURROGATE.md §7).
void add_probe_commands(CLI::App& app);
}  // namespace experiments
