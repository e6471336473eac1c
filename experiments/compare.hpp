#pragma once
// `tissue compare`: the FEM reference and both meshless variants (enrichment = the proposed model,
// visibility = the baseline) on one case, evaluated at the same sample points (paper §5.4, eqs. 33–34).
// The comparator sees only ModelResult (sample displacements and timings), never a model's inside, so another
// program's samples (`--external NAME=FILE.csv`, role "external") are scored by the same code.
//
// Files written to the output folder (docs/EXPERIMENTS.md lists every column):
//   case.json, samples.csv, summary.json, table.md, radar.png, samples.vtu,
//   {fem,enrichment,visibility}/timings.json and, when case.output.vtu, their displacement_NNN.vtu.
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "experiments/compare_metrics.hpp"
#include "experiments/external_result.hpp"
#include "experiments/model_result.hpp"

namespace experiments {

struct CompareOptions {
  std::string out_dir;
  /// [m] flag samples this close to the load-patch circle; default: a quarter of the load radius.
  std::optional<double> patch_edge_distance;
  /// [m] flag samples this close to the cut; default: the case's meshless node spacing.
  std::optional<double> cut_distance;
  /// A `tissue verify fem` result (fem.json) to take the reference's error bar from; a missing file only
  /// means the error bar is unknown.
  std::string reference_error_file = "results/verify/fem.json";
  bool plot = true;  ///< run scripts/plot_radar.py for radar.png
  /// Cut cases: also solve every model without the cut and report each model's cut effect against the FEM's.
  bool cut_effect = true;
  /// Which samples stand for the reference: "solved" (this run's FEM solve) or "extrapolated" (the
  /// Richardson-extrapolated samples of the mesh study in reference_error_file, which must have solved exactly this
  /// reference; their bar is the study's finest level's). The FEM is solved either way, to check the study.
  std::string reference_samples = "solved";
  /// Other programs' sample displacements to score beside the built-in models (`--external NAME=FILE`), in the
  /// order given; each is read and checked before any solve (experiments/external_result.hpp).
  std::vector<ExternalSpec> externals;

  bool IsValid(std::string* why) const;
};

/// The meshless variants, in the order they are run and reported: {name, meshless.enrichment value, role}.
struct MeshlessVariant {
  std::string name;
  std::string role;
};
const std::vector<MeshlessVariant>& meshless_variants();

/// Everything the writers need: the three results at the same samples and what the comparator derived.
struct Comparison {
  std::string case_name;
  std::string config;
  Eigen::MatrixXd sample_points;  ///< #samples by 3 [m]
  ModelResult reference;          ///< the FEM reference
  /// By name: the meshless variants, then the external results (role "external") in the order given.
  std::vector<std::pair<std::string, ModelResult>> models;
  SampleFlagRules rules;
  SampleDiagnostics diagnostics;
  ReferenceErrorBar error_bar;
  /// With CompareOptions::reference_samples "extrapolated": the FEM's own solved samples (#samples by 3 [m]), which
  /// `reference` then no longer holds.
  std::optional<Eigen::MatrixXd> solved_reference_samples;
  /// Cut cases: each model's own uncut solve at the same samples (#samples by 3 [m]), by model name ("fem" and each
  /// meshless variant), so that each model's cut effect (its cut solve minus its uncut solve) can be compared with the
  /// FEM's: the common discretisation error of the meshless model then cancels (docs/EXPERIMENTS.md, "The cut's own
  /// effect").
  std::vector<std::pair<std::string, Eigen::MatrixXd>> uncut_samples;
  double geometry_seconds = 0.0;  ///< building the geometry and both meshes, shared by the three models
  bool has_cut = false;
};

/// The names of the models compare solves itself: the reference ("fem") and the meshless variants.
std::vector<std::string> builtin_model_names();

/// summary.json: per meshless or external model the eq. 34 RMSE (all samples and without the flagged ones), relative to
/// the peak reference sample, beside the reference's error bar; the wall time of each phase per model.
nlohmann::json comparison_summary(const Comparison& comparison);
/// samples.csv: one row per sample and model (docs/EXPERIMENTS.md).
std::string comparison_samples_csv(const Comparison& comparison);
/// table.md: Table 1 of the paper for this case, the samples and the timings.
std::string comparison_table_md(const Comparison& comparison, const nlohmann::json& summary);

/// The runs.csv columns that `tissue sweep` takes from a summary.json, and their values for one summary.
const std::vector<std::string>& compare_row_columns();
std::vector<std::string> compare_row_values(const nlohmann::json& summary);

/// `tissue compare CONFIG --out DIR`; returns the exit code.
int run_compare(const std::string& config, const CompareOptions& options);

}  // namespace experiments
