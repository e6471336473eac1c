#pragma once
// A model-neutral result of one solve (FEM reference or meshless model), and the writers that put it in
// a results folder: samples.csv (eq. 33 displacements) and timings.json. The comparator reads these
// files and never looks inside a model.
#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/case.hpp"
#include "core/geometry.hpp"
#include "core/inadmissible_strain.hpp"
#include "core/step_cutback.hpp"

namespace experiments {

struct StepTiming {
  int step = 0;
  double time = 0.0;             ///< t_{n+1} [s]
  double wall_seconds = 0.0;
  double assembly_seconds = 0.0;
  double solve_seconds = 0.0;
  int iterations = 0;            ///< Newton iterations (linear solves)
  std::vector<double> residuals; ///< relative residual history
  int linear_iterations = 0;     ///< iterations of the linear solver over the step (0 for direct)
  int substeps = 1;              ///< converged sub-steps (more than 1 after a cut-back)
  std::vector<core::NewtonAttempt> failed_attempts;  ///< Newton attempts that failed and were cut back
  double admissibility_margin = 1.0;  ///< smallest 1 + 2k lambda at the converged state (docs/MATERIAL.md)
  /// Accelerated attempts that failed and were retried without acceleration at the same step (the EFG's
  /// meshless::StepRecord::retried_plain); they cost time, not a cut-back.
  std::vector<core::NewtonAttempt> retried_plain;
  /// Anderson-mixed updates that raised ||R|| and were replaced by the plain update (meshless::StepRecord::
  /// rejected_mixes, docs/MESHLESS.md §2); 0 for a model without the mixing.
  int rejected_mixes = 0;
};

struct ModelResult {
  std::string model;                    ///< "fem" or "meshless"
  /// "external" for another program's samples read from a CSV (experiments/models/external/external_result.hpp): no timings, no
  /// uncut solve, and never written back as timings.json. Empty for this program's own solves.
  std::string role;
  Eigen::MatrixXd sample_points;        ///< #samples by 3, reference coordinates [m]
  Eigen::MatrixXd sample_displacements; ///< #samples by 3 at the last step [m]
  double setup_seconds = 0.0;
  double total_seconds = 0.0;
  std::vector<StepTiming> steps;
  /// Per sample when the case has a cut (empty otherwise): its distance to the cut [m], and the lip the shared rule
  /// (core::RuledSurface::side) puts it on, +1 or -1 behind the crack front, 0 past it.
  std::vector<double> sample_cut_distance;
  std::vector<int> sample_lip;
  nlohmann::json details = nlohmann::json::object();  ///< model-specific figures (DOFs, sections, ...)
};


/// Fill sample_cut_distance and sample_lip from the geometry's cut (nothing without one).
void describe_samples_near_cut(const core::Geometry& geometry, ModelResult* result);

/// samples.csv: sample, x_mm, y_mm, z_mm, ux_mm, uy_mm, uz_mm, magnitude_mm (eq. 33: |x' - x|), cut_distance_mm
/// (empty without a cut), lip (+1 / -1 behind the cut's front, 0 elsewhere).
void write_samples_csv(const std::string& path, const ModelResult& result);
/// timings.json: setup, totals and per-step timings with Newton iterations and residuals.
nlohmann::json timings_json(const ModelResult& result);
void write_timings_json(const std::string& path, const ModelResult& result);
/// The smallest 1 + 2k lambda of a run, where it occurred, and the limit strain -1/(2k) (details of timings.json).
nlohmann::json admissibility_json(const core::SmallestMargin& smallest, const core::KelvinParameters& law);

/// Write `text` to `path`, replacing it; throws std::runtime_error naming the file when it cannot be opened
/// or when any byte fails to reach it (full disk, closed stream).
void write_text_file(const std::string& path, const std::string& text);

}  // namespace experiments
