#pragma once
// `tissue sweep SWEEP.json`: a base case, values to set for every run, and parameters (RFC 6901 JSON pointers
// into the case, each with a list of values; a zipped parameter names several pointers that take their values
// together); the runs are the Cartesian product of the parameter values. Optional compare options (the
// reference's samples and its mesh study) are passed to every run's `tissue compare`.
// Every generated case is validated with core::parse_case before anything runs. Each run is one
// `tissue compare` in a child process (a crash or an out-of-memory kill ends that run only); `workers` runs
// go at once. One row per finished run is appended to runs.csv; a rerun skips the runs already done.
//
// Folder layout (docs/EXPERIMENTS.md): OUT/runs.csv, OUT/summary.md, OUT/sweep.png, OUT/cases/<id>.json,
// OUT/runs/<id>/ (the compare results), OUT/logs/<id>.log. A run's id is a hash of its whole case document,
// so a changed base case or value makes a new run, never a stale match.
//
// Thread safety: run_sweep calls the run function from `workers` threads at once; rows are appended under a
// lock by the calling process only.
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace experiments {

struct SweepParameter {
  /// RFC 6901, e.g. /meshless/node_spacing. One pointer ("pointer" in the file), or several that vary together
  /// ("pointers": a zipped parameter).
  std::vector<std::string> pointers;
  bool zipped = false;                ///< given as "pointers": each value is an array of pointers.size() values
  std::vector<nlohmann::json> values; ///< as in the file: a value, or (zipped) an array of one value per pointer
  /// The value of pointers[j] in values[k].
  const nlohmann::json& value(std::size_t k, std::size_t j) const { return zipped ? values[k][j] : values[k]; }
};

/// Options passed to each run's `tissue compare` (the sweep file's "compare" object).
struct SweepCompareOptions {
  std::string reference;        ///< "" (compare's default), "solved" or "extrapolated": --reference
  std::string reference_error;  ///< "" or a fem.json, resolved against the sweep file's folder: --reference-error
  /// The command-line arguments for `tissue compare` ("" options left out).
  std::vector<std::string> arguments() const;
};

struct SweepSpec {
  std::string file;            ///< the sweep file, as given (named in every error)
  std::string name;
  std::string description;
  std::string base_case_file;  ///< resolved against the sweep file's folder
  nlohmann::json base_document;
  std::vector<std::pair<std::string, nlohmann::json>> set;  ///< pointer -> value, applied to every run
  std::vector<SweepParameter> parameters;
  SweepCompareOptions compare;
  int workers = 1;
  /// Every swept pointer, in parameter order (a zipped parameter's in its order): the runs.csv columns.
  std::vector<std::string> columns() const;
};

/// Read a sweep file (schema in docs/EXPERIMENTS.md). Throws core::CaseError naming the sweep file, the JSON
/// pointer in it and what was expected.
SweepSpec load_sweep(const std::string& path);

struct SweepRun {
  std::string id;                      ///< 16 hex digits: FNV-1a of the case document (and the compare options)
  std::vector<nlohmann::json> values;  ///< one per swept pointer (SweepSpec::columns)
  nlohmann::json document;             ///< the generated case, validated
};

/// The Cartesian product (the last parameter varies fastest). Every value and every generated case is
/// validated with core::parse_case; a failure throws core::CaseError naming the sweep file, the parameter's
/// value (/parameters/i/values/k, or /parameters/i/values/k/j for one pointer of a zipped parameter), the
/// pointer, the value and what the case schema expected. With "compare": {"reference": "extrapolated"}, every
/// run's case name and /geometry/mesh_size must be a level of the mesh study in reference_error (else
/// core::CaseError naming /compare/reference_error); whether its samples equal the level's is checked by the
/// run's compare once the FEM is solved.
std::vector<SweepRun> expand_sweep(const SweepSpec& spec);

/// What one run gave: the compare summary.json when it succeeded, the reason when not.
struct RunOutcome {
  bool ok = false;
  std::string error;
  nlohmann::json summary;
  double wall_seconds = 0.0;
};

/// Runs one generated case: `case_file` holds its document; results go to `run_dir`, output to `log_file`.
using RunFunction = std::function<RunOutcome(const SweepRun& run, const std::string& case_file,
                                             const std::string& run_dir, const std::string& log_file)>;

/// `tissue compare CASE --out RUN_DIR [--no-plot] [compare_arguments...]` in a child process of `tissue_binary`;
/// `threads` > 0 keeps the child to that many threads (thread_limit_environment), 0 leaves it all the cores.
RunFunction compare_in_child_process(const std::string& tissue_binary, bool plot,
                                     const std::vector<std::string>& compare_arguments = {}, int threads = 0);

struct SweepOptions {
  std::string out_dir;        ///< default results/sweeps/<name>
  int workers = 0;            ///< 0: the sweep file's value (default 1)
  bool retry_failed = true;   ///< rerun runs whose last row says failed
  bool plot = true;           ///< sweep.png through scripts/plot_sweep.py
  bool IsValid(std::string* why) const;
};

/// The children a sweep runs at once: --workers, else the sweep file's `workers`.
int sweep_workers(const SweepSpec& spec, const SweepOptions& options);

struct SweepReport {
  int total = 0;
  int skipped = 0;    ///< already finished in runs.csv
  int succeeded = 0;
  int failed = 0;
};

/// Run the pending runs of `runs` and append their rows to OUT/runs.csv. Throws std::runtime_error before
/// any run when OUT is locked by another sweep or runs.csv belongs to another sweep (different columns).
SweepReport run_sweep(const SweepSpec& spec, const std::vector<SweepRun>& runs, const SweepOptions& options,
                      const RunFunction& run_function);

/// The runs.csv header for a sweep: run_id, status, one column per swept pointer, the compare columns
/// (compare_row_columns), fem_rmse_vs_extrapolated_mm, wall_seconds, error.
std::vector<std::string> runs_csv_header(const SweepSpec& spec);

/// One CSV field: quoted (RFC 4180) when it holds a comma, a quote or a line break; line breaks become spaces
/// so that every row is one line.
std::string csv_field(const std::string& text);

/// runs.csv, appended one whole row at a time (one write(2) with O_APPEND, then fsync). Opening it removes a
/// half-written last line that a crash may have left, and checks the header.
class RunsCsv {
 public:
  /// Creates the file with `header` when missing or empty; throws std::runtime_error when its header differs.
  RunsCsv(const std::string& path, const std::vector<std::string>& header);
  /// run_id -> status of its last row ("ok" or "failed").
  const std::vector<std::pair<std::string, std::string>>& rows() const { return rows_; }
  std::string last_status(const std::string& run_id) const;
  bool repaired() const { return repaired_; }  ///< a half-written last line was removed on opening
  void append(const std::vector<std::string>& fields);

 private:
  std::string path_;
  std::size_t columns_;
  std::vector<std::pair<std::string, std::string>> rows_;
  bool repaired_ = false;
};

/// `tissue sweep`; returns the exit code (0 when every run succeeded, 1 when some failed).
int run_sweep_command(const std::string& sweep_file, const SweepOptions& options, bool dry_run,
                      const std::string& tissue_binary);

}  // namespace experiments
