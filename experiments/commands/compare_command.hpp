#pragma once
#include <CLI/CLI.hpp>

namespace experiments {

/// `tissue compare CONFIG --out DIR`: the case's reference and models (/compare) on one case (compare.hpp).
void add_compare_command(CLI::App& app);

}  // namespace experiments
