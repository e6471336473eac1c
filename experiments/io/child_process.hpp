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
/// (appended; created when missing), or are inherited when `log_path` is empty.
ProcessOutcome run_process(const std::vector<std::string>& argv, const std::string& log_path);

/// The Python interpreter for the plot scripts: $TISSUE_PYTHON when set, else Debian's /usr/bin/python3 (where
/// python3-matplotlib lives) when it exists, else `python3` from PATH.
std::string plot_python();

}  // namespace experiments
