#pragma once
// The meshless (EFG) model behind `tissue solve meshless` (solve_commands.cpp) and `tissue verify meshless`
// (verify_commands.cpp).
#include <chrono>
#include <functional>
#include <optional>
#include <string>

#include "core/case.hpp"
#include "core/geometry.hpp"
#include "core/inadmissible_strain.hpp"
#include "core/ruled_surface.hpp"
#include "experiments/models/model_result.hpp"
#include "meshless/efg/efg_model.hpp"
#include "meshless/efg/efg_problem.hpp"

namespace experiments {

/// Solve the case with the EFG model; VTU per output step goes to `vtu_prefix`_NNN.vtu (the node cloud's cells
/// with the displacement at the nodes) and, for a cut body, `vtu_prefix`_lips_NNN.vtu (both lips of the cut, each
/// with its own displacement: the opened cut) when the prefix is not empty. `on_step` gets a progress line per step.
/// With `progressive_cut` the case's cut is not there at once: it advances along its polyline in /cut/steps equal
/// increments, one at the start of each of the first /cut/steps time steps (a local update of the shape functions,
/// meshless::EfgModel::advance_cut, then the step's solve, with the history carried over).
ModelResult solve_meshless(const core::Case& c, const core::Geometry& g, const std::string& vtu_prefix,
                           const std::function<void(const std::string&)>& on_step = {},
                           const meshless::EfgOptions& options = {}, bool progressive_cut = false);

/// EfgModel::setup_system with the case's advice when a point has too few nodes (SingularMomentMatrix), and one
/// progress line describing the model.
void set_up_meshless(meshless::EfgModel& model, const core::Case& c,
                     const std::function<void(const std::string&)>& on_step = {});

/// How run_meshless_steps runs a set-up (or restarted) model through the case's steps.
struct MeshlessRun {
  int cut_increments = 1;                      ///< > 1: the cut advances to full_cut over this many first steps
  std::optional<core::RuledSurface> full_cut;  ///< the case's whole cut (with cut_increments > 1)
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();  ///< the result's total from here
  meshless::EfgTimings timings_before;         ///< model.timings() before this run: the result reports the rest
};

/// The time steps of solve_meshless on a model already set up (or restarted under the case's load), into the
/// comparator's result: samples, per-step timings, details.
ModelResult run_meshless_steps(meshless::EfgModel& model, const core::Case& c, const core::Geometry& g,
                               const std::string& vtu_prefix, const std::function<void(const std::string&)>& on_step,
                               const MeshlessRun& run);

/// What to change when the EFG's strain left the law's admissible range (e) beside a cut's front: within one node
/// spacing of the front the cause is the enrichment's sharp front (docs/MESHLESS.md §5.2), not the load, so the
/// generic advice of `e` (a smaller force, a larger patch) would mislead. Empty elsewhere or without a cut.
/// solve_meshless appends it to the error.
std::string front_transition_hint(const core::InadmissibleStrain& e, const core::MeshlessSpec& spec,
                                  const std::optional<core::RuledSurface>& cut, double front_transition);

/// `tissue verify meshless`: invariants, patch test, cantilever convergence and creep curve into
/// OUT/meshless.json and OUT/meshless.md.
int run_verify_meshless(const std::string& out_dir, bool quick);

}  // namespace experiments
