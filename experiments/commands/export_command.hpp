#pragma once
#include <CLI/CLI.hpp>

namespace experiments {
/// `tissue export CASE --out DIR` (the reference's problem for another FE program) and `tissue import-ccx` (CalculiX's
/// answer back at the samples). experiments/export/case_export.hpp.
void add_export_commands(CLI::App& app);
}  // namespace experiments
