#pragma once
// Run the `tissue` program as a child process (TISSUE_BINARY, set by tests/CMakeLists.txt) and keep what it printed:
// the command-line suites check exit codes and messages this way (run_command: any command line, e.g. under mpirun).
#include <cstdio>
#include <string>
#include <array>
#include <sys/wait.h>

namespace tissue_test {

struct TissueRun {
  int exit_code;
  std::string output;  ///< stdout and stderr
};

/// Run a shell command line and keep what it printed (stdout and stderr).
inline TissueRun run_command(const std::string& command) {
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  std::string output;
  std::array<char, 4096> buffer{};
  while (pipe && fgets(buffer.data(), buffer.size(), pipe)) output += buffer.data();
  const int status = pipe ? pclose(pipe) : -1;
  return {WEXITSTATUS(status), output};
}

inline TissueRun run_tissue(const std::string& args) { return run_command(std::string(TISSUE_BINARY) + " " + args); }

}  // namespace tissue_test
