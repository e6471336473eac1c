#pragma once
// Run a child program and wait for it (POSIX posix_spawnp + waitpid). The comparator runs its plot script
// this way, and `tissue sweep` runs each `tissue compare` as a child, so that a crash or an out-of-memory
// kill of one run cannot take the sweep down. Thread-safe: each call owns its child.
#include <string>
#include <vector>

namespace experiments {

struct ProcessOutcome {
  bool started = false;    ///< false when the program could not be started (see `error`)
  int exit_code = -1;      ///< valid when the child exited normally
  int signal = 0;          ///< non-zero when the child was killed by a signal
  std::string error;       ///< why it could not start, or a summary of how it ended
  bool ok() const { return started && signal == 0 && exit_code == 0; }
};

/// Run argv[0] (searched in PATH when it has no '/') with `argv`; its stdout and stderr go to `log_path`
/// (appended; created when missing), or are inherited when `log_path` is empty. The child inherits this process's
/// environment, with each "NAME=value" of `environment` added or replacing the variable of that name.
ProcessOutcome run_process(const std::vector<std::string>& argv, const std::string& log_path,
                           const std::vector<std::string>& environment = {});

/// The last line of `file` that starts with `prefix`, or "" (a child's latest progress line: prefix "[").
std::string last_line_starting_with(const std::string& file, const std::string& prefix);

/// The last line of a child's log that starts with "error: " (a `tissue` command's own report of why it failed),
/// without that prefix, or "".
std::string last_error_line(const std::string& log_file);

/// Why a child that ended badly failed: its log's own `error:` line with how it ended in brackets, or only how it
/// ended when the log has none.
std::string child_failure(const ProcessOutcome& outcome, const std::string& log_file);

/// The last `lines` lines of a text file (fewer when it is shorter), for a failure report.
std::string tail_of_file(const std::string& file, int lines);

/// The environment (for run_process) that keeps a child `tissue` to `threads` threads of computation: deal.II's
/// task pool (the FEM's assembly), OpenMP's (the meshless models' loops) and OpenBLAS's. Children run side by side
/// get a share of the cores each, so that none of them waits for a core another one's threads hold.
std::vector<std::string> thread_limit_environment(int threads);

/// Each child's share of this machine's cores when `children` run at once: max(1, cores / children).
int threads_per_child(int children);

/// This running program's file (/proc/self/exe), for children that run it again (`tissue sweep`'s runs, `tissue
/// reproduce`'s Table 1 cases). Throws when the file was replaced on disk since this process started (a rebuild):
/// the children would run another program.
std::string this_program();

/// The Python interpreter for the plot scripts: $TISSUE_PYTHON when set, else Debian's /usr/bin/python3 (where
/// python3-matplotlib lives) when it exists, else `python3` from PATH.
std::string plot_python();

}  // namespace experiments
