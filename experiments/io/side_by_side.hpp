#pragma once
// Child programs run side by side, a few at a time, each kept to its share of the cores. `tissue reproduce` runs
// its Table 1 cases this way: a second thread speeds one process of the FEM and the meshless models up by only
// 1.17-1.68x (docs/PERFORMANCE.md, "Table 1's cases side by side"), so two of them at one thread each finish sooner
// than one after the other at two.
//
// Thread safety: run_side_by_side is called from one thread; it starts one waiting thread per child running and
// prints (through `progress`) only from the calling thread.
#include <string>
#include <vector>

#include "experiments/io/child_process.hpp"

namespace experiments {

class Progress;

struct ChildJob {
  std::string label;              ///< names the job in the progress lines
  std::vector<std::string> argv;  ///< the program and its arguments (run_process)
  std::string log_file;           ///< the child's stdout and stderr (created, appended)
};

struct SideBySideOptions {
  int children = 2;           ///< how many run at once
  int threads_per_child = 1;  ///< each child's threads (thread_limit_environment)
  /// While children run, each one's latest progress line (the last line of its log that starts with '[') is
  /// printed this often [s]; so a long run is never silent.
  double status_interval_seconds = 30.0;
  bool IsValid(std::string* why) const;
};

/// Run `jobs`, `options.children` at a time in list order, and wait for all of them: a failed child does not stop
/// the others. Prints through `progress` one step per job as it starts (with its log) and a note as it ends (its
/// wall time, or how it failed). Returns each job's outcome, in the order of `jobs`.
std::vector<ProcessOutcome> run_side_by_side(const std::vector<ChildJob>& jobs, const SideBySideOptions& options,
                                             Progress* progress);

}  // namespace experiments
