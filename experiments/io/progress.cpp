#include "experiments/io/progress.hpp"

#include <fmt/format.h>

#include <iostream>

namespace experiments {

Progress::Progress(std::string task, int total_steps, bool quiet)
    : task_(std::move(task)), total_(total_steps), quiet_(quiet), start_(std::chrono::steady_clock::now()) {}

double Progress::elapsed_seconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void Progress::step(const std::string& what) {
  ++current_;
  if (quiet_) return;
  std::cerr << fmt::format("[{} {}/{}] {} (t = {:.1f} s)\n", task_, current_, total_, what, elapsed_seconds());
}

void Progress::note(const std::string& what) {
  if (!quiet_) std::cerr << fmt::format("[{}] {} (t = {:.1f} s)\n", task_, what, elapsed_seconds());
}

void Progress::done() {
  if (!quiet_) std::cerr << fmt::format("[{}] done in {:.1f} s\n", task_, elapsed_seconds());
}

}  // namespace experiments
