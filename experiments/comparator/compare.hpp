#pragma once
// `tissue compare`: the case's reference and its scored models (/compare: by default the FEM reference and both
// meshless variants, enrichment = the proposed model, visibility = the baseline) on one case, evaluated at the same
// sample points (paper §5.4, eqs. 33–34). The comparator sees models only through experiments/models/model.hpp and
// their ModelResult (sample displacements and timings), never a model's inside, so another program's samples
// (`--external NAME=FILE.csv`, role "external") are scored by the same code.
//
// Files written to the output folder (docs/EXPERIMENTS.md lists every column):
//   case.json, samples.csv, summary.json, table.md, radar.png, samples.vtu,
//   MODEL/timings.json for every solved model and, when case.output.vtu, its displacement_NNN.vtu.
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/case.hpp"
#include "experiments/comparator/compare_metrics.hpp"
#include "experiments/models/external/external_result.hpp"
#include "experiments/models/model_result.hpp"

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
  /// Mesh studies (fem.json) of this case's problem in another mesh family, their levels averaged by size
  /// (experiments/comparator/mesh_family_error_bar.hpp); when given, the error bar and the extrapolated samples are
  /// theirs instead of reference_error_file's. Read and checked before any solve.
  std::vector<std::string> reference_family;
  bool plot = true;  ///< run scripts/plot_radar.py for radar.png
  /// Cut cases: also solve every model without the cut and report each model's cut effect against the FEM's.
  bool cut_effect = true;
  /// Which samples stand for the reference: "solved" (this run's FEM solve) or "extrapolated" (the
  /// Richardson-extrapolated samples of the mesh study in reference_error_file, which must have solved exactly this
  /// reference, or of the reference_family; their bar is the study's finest level's). The FEM is solved either way,
  /// to check the study.
  std::string reference_samples = "solved";
  /// Other programs' sample displacements to score beside the built-in models (`--external NAME=FILE`), in the
  /// order given; each is read and checked before any solve (experiments/models/external/external_result.hpp).
  std::vector<ExternalSpec> externals;

  bool IsValid(std::string* why) const;
};

/// A model of the case's list that was not solved, and why (Model::cannot_solve).
struct NotSolved {
  std::string name;
  std::string role;
  std::string why;
};

/// Everything the writers need: every model's result at the same samples and what the comparator derived.
struct Comparison {
  std::string case_name;
  std::string config;
  Eigen::MatrixXd sample_points;      ///< #samples by 3 [m]
  std::string reference_name = "fem";  ///< the case's /compare/reference
  ModelResult reference;
  /// By name, in the case's /compare/models order (those solved), then the external results (role "external") in
  /// the order given. ModelResult::role holds each model's role (Model::role).
  std::vector<std::pair<std::string, ModelResult>> models;
  std::vector<NotSolved> not_solved;  ///< models of the case's list that cannot solve it, in list order
  SampleFlagRules rules;
  SampleDiagnostics diagnostics;
  ReferenceErrorBar error_bar;
  /// With CompareOptions::reference_samples "extrapolated": the FEM's own solved samples (#samples by 3 [m]), which
  /// `reference` then no longer holds.
  std::optional<Eigen::MatrixXd> solved_reference_samples;
  /// Cut cases: each model's own uncut solve at the same samples (#samples by 3 [m]), by model name (the reference and
  /// each solved model but the external ones), so that each model's cut effect (its cut solve minus its uncut solve) can be compared with the
  /// FEM's: the common discretisation error of the meshless model then cancels (docs/EXPERIMENTS.md, "The cut's own
  /// effect").
  std::vector<std::pair<std::string, Eigen::MatrixXd>> uncut_samples;
  double geometry_seconds = 0.0;  ///< building the geometry and the meshes, shared by every model
  bool has_cut = false;
};

/// summary.json: per scored model (and external result) the eq. 34 RMSE (all samples and without the flagged ones),
/// relative to the peak reference sample, beside the reference's error bar; the wall time of each phase per model.
/// With a "proposed" and a "baseline" model, their difference (the third column of the paper's Table 1).
nlohmann::json comparison_summary(const Comparison& comparison);
/// samples.csv: one row per sample and model (docs/EXPERIMENTS.md).
std::string comparison_samples_csv(const Comparison& comparison);
/// table.md: Table 1 of the paper for this case, the samples and the timings.
std::string comparison_table_md(const Comparison& comparison, const nlohmann::json& summary);

/// The runs.csv columns that `tissue sweep` takes from a summary.json, for the scored models `models` (a sweep's base
/// case's /compare/models), and their values for one summary. The fem_* columns are the reference's, whatever model
/// it is; a model missing from the summary (not solved) leaves its columns empty.
std::vector<std::string> compare_row_columns(const std::vector<std::string>& models = core::CompareSpec{}.models);
std::vector<std::string> compare_row_values(const nlohmann::json& summary,
                                            const std::vector<std::string>& models = core::CompareSpec{}.models);

/// The role's kind: the word before its colon ("proposed" of "proposed: the EFG with ...").
std::string role_kind(const std::string& role);

/// `tissue compare CONFIG --out DIR`; returns the exit code.
int run_compare(const std::string& config, const CompareOptions& options);

}  // namespace experiments
