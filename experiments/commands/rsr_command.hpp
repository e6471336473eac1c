#pragma once
#include <CLI/CLI.hpp>

namespace experiments {

/// `tissue rsr [SCORES.csv] [--lower-is-better I...] [--out DIR]`: the rank-sum-ratio evaluation of §5.6.
void add_rsr_command(CLI::App& app);

}  // namespace experiments
