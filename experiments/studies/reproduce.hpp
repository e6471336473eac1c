#pragma once
// `tissue reproduce`: the paper's Table 1 (§5.4: the RMSE of the proposed model and of the baseline meshless
// cutting model against the FEM reference) and the analogue of its Fig. 9 (§5.5: the time to compute one
// deformation result for 8 forces in 0-4 N at one stressed point), on the cases a plan file names.
//
// Files written to the output folder (default results/reproduce/, written atomically; docs/EXPERIMENTS.md):
//   plan.json            the plan as run
//   table1.md/.json      our RMSEs beside the paper's, with the reference's error bar
//   <label>/             each Table 1 case's full `tissue compare` folder
//   <label>.log          while the cases run side by side (ReproduceOptions::jobs), that child's output; removed
//                        when it succeeds
//   timing.md/.json      per force: the full meshless solve, the FEM reference and the surrogate's query (when
//                        the plan names a surrogate case: trained once, then queried)
//   timing.png           the timing as grouped bars (scripts/plot_timing.py)
#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace meshless {
class Surrogate;
}

namespace experiments {

struct CompareOptions;

/// What `tissue reproduce` runs (configs/reproduce.json). Case paths are relative to the plan's folder.
struct ReproducePlan {
  struct Table1Case {
    std::string label;   ///< row label and sub-folder, e.g. "small deformation"
    std::string config;  ///< the case, resolved to a path
    double paper_enrichment_mm = 0.0;  ///< the paper's Table 1: proposed model
    double paper_visibility_mm = 0.0;  ///< the paper's Table 1: interactive meshless cutting model
    /// Sweep folders over this case's node cloud (resolved; experiments/studies/cloud_change.hpp): the meshless
    /// model's own change between clouds, which the verdict combines with the reference's error bar.
    std::vector<std::string> cloud_studies;
    /// fem.json files (resolved) of this case's problem in another mesh family, whose levels are averaged by size:
    /// the reference's error bar is measured against them (CompareOptions::reference_family); empty: compare's
    /// --reference-error default, the study of this very reference.
    std::vector<std::string> reference_family;
  };
  struct Timing {
    std::string config;          ///< the case whose load point is stressed, resolved to a path
    std::vector<double> forces;  ///< force magnitudes [N] along the case's force direction
    int steps = 1;               ///< time steps per deformation result (replaces /time/steps)
    /// A case with a /surrogate block whose contact points include the load point (resolved to a path), or
    /// empty: the surrogate is trained on it (as `tissue fit` does) and queried at each force.
    std::string surrogate_config;
    /// The models timed (replaces the case's /compare/models; the reference is always timed), or empty: the case's
    /// own list. So the timing can show a model that the case's other users (the CI gates) do not run.
    std::vector<std::string> models;
  };
  std::string file;
  std::vector<Table1Case> table1;
  Timing timing;
};

/// Read and check a plan; errors are core::CaseError naming the file and the JSON pointer.
ReproducePlan load_reproduce_plan(const std::string& file);

/// The Fig. 9 column of the surrogate: for each force magnitude (along `direction`, at `point` [m]), the median
/// wall time of `queries` calls of surrogate.query [s] and its answer (contact displacement [mm], flags), one JSON
/// row per force.
nlohmann::json surrogate_query_timing(const meshless::Surrogate& surrogate, const Eigen::Vector3d& point,
                                      const Eigen::Vector3d& direction, const std::vector<double>& forces,
                                      int queries);

struct ReproduceOptions {
  std::string plan = "configs/reproduce.json";
  std::string out_dir = "results/reproduce";
  bool plot = true;
  bool table1 = true;  ///< false: the timing only
  bool timing = true;  ///< false: Table 1 only
  /// Table 1's cases run at once, each `tissue compare` a child process of `tissue_binary` kept to its share of the
  /// cores (experiments/io/side_by_side.hpp); 0: as many as cores, up to the cases; 1: one after the other in this
  /// process. The timing runs alone afterwards either way: its figures are speeds.
  int jobs = 0;
  std::string tissue_binary;  ///< the `tissue` program the children run (needed when more than one case runs at once)
  bool IsValid(std::string* why) const;
  /// How many of `cases` Table 1 cases run at once.
  int table1_children(int cases) const;
};

/// A Table 1 case's compare as a `tissue compare` command line of `tissue_binary` (how the cases run side by side):
/// the options reproduce sets (out_dir, plot, reference_family) as compare's flags.
std::vector<std::string> compare_command_line(const std::string& tissue_binary, const std::string& config,
                                              const CompareOptions& compare);

/// `tissue reproduce`; returns the exit code.
int run_reproduce(const ReproduceOptions& options);

/// timing.md from timing.json: per force each timed model's time for one result (`= set-up once + solve` for a model
/// set up once per cloud, Model::prepare_load_series), the ratios of the full times and of the solves alone, and the
/// surrogate's query.
std::string timing_md(const nlohmann::json& timing);

/// One row of table1.json from a `tissue compare` summary.json: one entry per scored model of the case (its /compare
/// list; a model that could not solve the case, or whose solve failed, says why), with the paper's figures beside.
nlohmann::json table1_row(const ReproducePlan::Table1Case& t, const nlohmann::json& summary);

/// Table 1's verdict on one row of table1.json: which of the proposed model and the baseline is closer to the
/// reference, and whether their difference stands out of the reference's error bar and the meshless model's own
/// change between node clouds, combined as sqrt(bar^2 + change^2).
std::string table1_verdict(const nlohmann::json& row);

/// table1.md from the rows of table1.json (table1_row, with "cloud_change" and "cloud_change_versus_extrapolated"
/// added): one column per model, the difference, the bars, the verdict and the paper's figures; then footnotes (the
/// runs behind each cloud change, the models not solved) and what the columns mean.
std::string table1_md(const nlohmann::json& rows);

}  // namespace experiments
