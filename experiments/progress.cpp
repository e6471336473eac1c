#include "experiments/progress.hpp"

#include <fmt/format.h>

#include <iostream>

namespace experiments {

Progress::Progress(std::string task, int total_steps)
    : task_(std::move(task)), total_(total_steps), start_(std::chrono::steady_clock::now()) {}

double Progress::elapsed_seconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void Progress::step(const std::string& what) {
  ++current_;
  std::cerr << fmt::format("[{} {}/{}] {} (t = {:.1f} s)\n", task_, current_, total_, what, elapsed_seconds());
}

void Progress::done() { std::cerr << fmt::format("[{}] done in {:.1f} s\n", task_, elapsed_seconds()); }

}  // namespace experiments
