#pragma once
// Training, fitting and validation of the surrogate in one recipe (paper §3; docs/SURROGATE.md):
//   1. snap the contact points to surface nodes of the fixed cloud;
//   2. solve the full meshless model for every contact node, axis and signed force level
//   (surrogate_training);
//   3. fit eqs. 25-28 with cross-validated orders (surrogate_fit);
//   4. solve held-out forces that were not trained on and compare the surrogate with them.
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "core/case.hpp"
#include "meshless/efg/efg_problem.hpp"
#include "meshless/surrogate/surrogate.hpp"
#include "meshless/surrogate/surrogate_fit.hpp"
#include "meshless/surrogate/surrogate_training.hpp"

namespace meshless {

/// The fit knobs of a case's /surrogate block.
SurrogateFitOptions fit_options(const core::SurrogateSpec& spec);

/// Trained signed levels: +-max_force * m / force_levels, m = 1..force_levels, increasing.
std::vector<double> training_levels(const core::SurrogateSpec& spec);

/// Deterministic forces the surrogate was not trained on: even ones along one axis half-way between two
/// trained levels, odd ones oblique (all three components, which also tests the superposition), cycling over
/// the contacts.
std::vector<PatchLoad> holdout_loads(const core::SurrogateSpec& spec, const std::vector<int>& contacts);

/// The held-out loads at a contact region's untrained nodes: every one of holdout_loads() at each node.
std::vector<PatchLoad> region_holdout_loads(const core::SurrogateSpec& spec, const std::vector<int>& nodes);

/// One held-out comparison.
struct HoldoutError {
  PatchLoad load;
  double rmse = 0.0;  ///< [m] eq. 34 over every surface node: surrogate against the full model
  double contact_displacement = 0.0;  ///< [m] |u| of the full model at the contact node
  double relative = 0.0;              ///< rmse / contact_displacement
  double contact_error = 0.0;         ///< [m] |u_surrogate - u_full| at the contact node
  bool trained_contact = true;  ///< false: an untrained node of the contact region (the interpolation's error)
  /// On a cut body: the same RMSE over the surface nodes within one node spacing of the cut (its lips) and over
  /// the others [m]; NaN without a cut.
  double rmse_near_cut = std::numeric_limits<double>::quiet_NaN();
  double rmse_away_from_cut = std::numeric_limits<double>::quiet_NaN();
};

struct SurrogateBuildOptions {
  EfgOptions efg;
  double memory_budget_bytes = 4e9;  ///< PatchSolveOptions::memory_budget_bytes
  int max_workers = 0;               ///< PatchSolveOptions::max_workers
};

struct SurrogateBuildReport {
  std::vector<double> snap_distance;  ///< [m] per contact point, to its surface node (a region: its centre)
  RegionContacts region;              ///< the contact region's nodes (empty without a region)
  double near_cut_distance = 0.0;     ///< [m] on a cut body: "near the lips" means within this of the cut
  PatchSolveReport training, holdout;
  int training_solves = 0;
  double fit_seconds = 0.0;
  double peak_contact_displacement = 0.0;  ///< [m] largest |u| of a contact node over the training data
  std::vector<HoldoutError> holdouts;
  /// The data behind the fits and the held-out check, to refit or compare without solving again.
  std::vector<ContactTrainingData> training_data;
  std::vector<PatchLoad> holdout_loads;
  std::vector<SolvedLoad> holdout_solves;
};

/// Build the surrogate of `problem`'s cloud (its penalised faces, material, ramp and steps) as `spec` asks.
/// The case name and hash are the caller's to fill. `progress` (may be empty) gets a line per solve and fit.
SurrogateData build_surrogate(const EfgProblem& problem, const core::SurrogateSpec& spec,
                              const SurrogateBuildOptions& options,
                              const std::function<void(const std::string&)>& progress = {},
                              SurrogateBuildReport* report = nullptr);

/// Compare the surrogate with full solves (eq. 34 RMSE over the surface nodes, per load).
/// `near_cut` (may be null): #S mask of the surface nodes near a cut, for HoldoutError::rmse_near_cut.
std::vector<HoldoutError> holdout_errors(const Surrogate& surrogate, const std::vector<PatchLoad>& loads,
                                         const std::vector<SolvedLoad>& full,
                                         const std::vector<char>* near_cut = nullptr);

}  // namespace meshless
