#include "experiments/io/child_process.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <thread>

extern char** environ;

namespace experiments {

namespace {

/// This process's environment with `overrides` ("NAME=value") added or replacing the variables of their names.
std::vector<std::string> merged_environment(const std::vector<std::string>& overrides) {
  std::vector<std::string> merged;
  const auto name_of = [](const std::string& entry) { return entry.substr(0, entry.find('=')); };
  for (char** e = environ; *e; ++e) {
    const std::string entry(*e);
    if (std::none_of(overrides.begin(), overrides.end(),
                     [&](const std::string& o) { return name_of(o) == name_of(entry); }))
      merged.push_back(entry);
  }
  merged.insert(merged.end(), overrides.begin(), overrides.end());
  return merged;
}

}  // namespace

std::vector<std::string> thread_limit_environment(int threads) {
  const std::string n = std::to_string(std::max(1, threads));
  return {"DEAL_II_NUM_THREADS=" + n, "OMP_NUM_THREADS=" + n, "OPENBLAS_NUM_THREADS=" + n};
}

int threads_per_child(int children) {
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  return std::max(1, cores / std::max(1, children));
}

ProcessOutcome run_process(const std::vector<std::string>& argv, const std::string& log_path,
                           const std::vector<std::string>& environment) {
  ProcessOutcome outcome;
  if (argv.empty()) {
    outcome.error = "no program to run";
    return outcome;
  }
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (!log_path.empty()) {
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log_path.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  }
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  std::vector<std::string> env_entries;
  std::vector<char*> env;
  if (!environment.empty()) {
    env_entries = merged_environment(environment);
    for (auto& e : env_entries) env.push_back(e.data());
    env.push_back(nullptr);
  }
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), env.empty() ? environ : env.data());
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) {
    outcome.error = "cannot start " + argv[0] + ": " + std::strerror(rc);
    return outcome;
  }
  outcome.started = true;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) {
      outcome.error = std::string("waitpid failed: ") + std::strerror(errno);
      return outcome;
    }
  }
  if (WIFEXITED(status)) {
    outcome.exit_code = WEXITSTATUS(status);
    if (outcome.exit_code != 0) outcome.error = argv[0] + " exited with status " + std::to_string(outcome.exit_code);
  } else if (WIFSIGNALED(status)) {
    outcome.signal = WTERMSIG(status);
    outcome.error = argv[0] + " was killed by signal " + std::to_string(outcome.signal) + " (" +
                    strsignal(outcome.signal) + ")";
  }
  return outcome;
}

/// The last line of `file` that starts with `prefix`, or "".
std::string last_line_starting_with(const std::string& file, const std::string& prefix) {
  std::ifstream in(file);
  std::string line, last;
  while (std::getline(in, line))
    if (line.rfind(prefix, 0) == 0) last = line;
  return last;
}

std::string last_error_line(const std::string& log_file) {
  const std::string line = last_line_starting_with(log_file, "error: ");
  return line.empty() ? line : line.substr(7);
}

std::string child_failure(const ProcessOutcome& outcome, const std::string& log_file) {
  const std::string error = last_error_line(log_file);
  return error.empty() ? outcome.error : error + " (" + outcome.error + ")";
}

std::string tail_of_file(const std::string& file, int lines) {
  std::ifstream in(file);
  std::deque<std::string> kept;
  for (std::string line; std::getline(in, line);) {
    kept.push_back(line);
    if (static_cast<int>(kept.size()) > lines) kept.pop_front();
  }
  std::string text;
  for (const auto& l : kept) text += l + "\n";
  return text;
}

std::string this_program() {
  const std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
  const std::string deleted = " (deleted)";
  if (self.size() > deleted.size() && self.compare(self.size() - deleted.size(), deleted.size(), deleted) == 0)
    throw std::runtime_error("the tissue program was replaced on disk after this command started (a rebuild?); "
                             "start the command again");
  return self;
}

std::string plot_python() {
  if (const char* env = std::getenv("TISSUE_PYTHON"); env && *env) return env;
  if (std::filesystem::exists("/usr/bin/python3")) return "/usr/bin/python3";
  return "python3";
}

}  // namespace experiments
