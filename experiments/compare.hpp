#pragma once
// `tissue compare`: the FEM reference and both meshless variants (enrichment = the proposed model,
// visibility = the baseline) on one case, evaluated at the same sample points (paper §5.4, eqs. 33–34).
// The comparator sees only ModelResult (sample displacements and timings), never a model's inside.
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
  std::vector<std::pair<std::string, ModelResult>> models;  ///< meshless variants by name
  SampleFlagRules rules;
  SampleDiagnostics diagnostics;
  ReferenceErrorBar error_bar;
  double geometry_seconds = 0.0;  ///< building the geometry and both meshes, shared by the three models
  bool has_cut = false;
};

/// summary.json: per meshless model the eq. 34 RMSE (all samples and without the flagged ones), relative to
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
