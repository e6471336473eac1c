#pragma once
// The meshless (EFG) model behind `tissue solve meshless` (solve_commands.cpp) and `tissue verify meshless`
// (verify_commands.cpp).
#include <functional>
#include <string>

#include "core/case.hpp"
#include "core/geometry.hpp"
#include "experiments/model_result.hpp"
#include "meshless/efg_problem.hpp"

namespace experiments {

/// Solve the case with the EFG model; VTU per output step goes to `vtu_prefix`_NNN.vtu when not empty.
/// `on_step` gets a progress line per step.
ModelResult solve_meshless(const core::Case& c, const core::Geometry& g, const std::string& vtu_prefix,
                           const std::function<void(const std::string&)>& on_step = {},
                           const meshless::EfgOptions& options = {});

/// `tissue verify meshless`: invariants, patch test, cantilever convergence and creep curve into
/// OUT/meshless.json and OUT/meshless.md.
int run_verify_meshless(const std::string& out_dir, bool quick);

}  // namespace experiments
