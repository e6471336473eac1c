#pragma once
#include <CLI/CLI.hpp>

namespace experiments {
/// `tissue fit CONFIG --out FILE`: train and fit the force -> displacement surrogate (paper §3,
/// docs/SURROGATE.md), and `tissue fit CONFIG --check-patch`: the training patch against the case's imprinted
/// load patch.
void add_fit_commands(CLI::App& app);
}  // namespace experiments
