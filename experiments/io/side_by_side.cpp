#include "experiments/io/side_by_side.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "experiments/io/progress.hpp"

namespace experiments {

bool SideBySideOptions::IsValid(std::string* why) const {
  const auto fail = [&](const char* what) {
    if (why) *why = what;
    return false;
  };
  if (children < 1) return fail("children must be >= 1");
  if (threads_per_child < 1) return fail("threads_per_child must be >= 1");
  if (!(status_interval_seconds > 0.0)) return fail("status_interval_seconds must be > 0");
  return true;
}

std::vector<ProcessOutcome> run_side_by_side(const std::vector<ChildJob>& jobs, const SideBySideOptions& options,
                                             Progress* progress) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("run_side_by_side: " + why);
  enum class State { waiting, running, ended };
  struct Slot {
    State state = State::waiting;
    bool announced_start = false, announced_end = false;
    std::chrono::steady_clock::time_point started;
    double wall_seconds = 0.0;
  };
  std::vector<ProcessOutcome> outcomes(jobs.size());
  std::vector<Slot> slots(jobs.size());
  std::mutex mutex;
  std::condition_variable changed;
  std::size_t next = 0;
  const std::vector<std::string> environment = thread_limit_environment(options.threads_per_child);

  // Each runner takes the next job, runs it and records how it ended; the calling thread does all the printing.
  const auto runner = [&] {
    for (;;) {
      std::size_t i;
      {
        std::lock_guard<std::mutex> lock(mutex);
        if (next == jobs.size()) return;
        i = next++;
        slots[i].state = State::running;
        slots[i].started = std::chrono::steady_clock::now();
      }
      changed.notify_all();
      ProcessOutcome outcome = run_process(jobs[i].argv, jobs[i].log_file, environment);
      {
        std::lock_guard<std::mutex> lock(mutex);
        outcomes[i] = std::move(outcome);
        slots[i].wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - slots[i].started).count();
        slots[i].state = State::ended;
      }
      changed.notify_all();
    }
  };
  std::vector<std::thread> runners;
  for (int r = 0; r < std::min<int>(options.children, static_cast<int>(jobs.size())); ++r) runners.emplace_back(runner);

  std::unique_lock<std::mutex> lock(mutex);
  for (;;) {
    bool news = false;
    for (std::size_t i = 0; i < jobs.size(); ++i) {
      Slot& s = slots[i];
      if (s.state != State::waiting && !s.announced_start) {
        s.announced_start = news = true;
        progress->step(fmt::format("{}: started beside the others ({} thread{}; log {})", jobs[i].label,
                                   options.threads_per_child, options.threads_per_child == 1 ? "" : "s",
                                   jobs[i].log_file));
      }
      if (s.state == State::ended && !s.announced_end) {
        s.announced_end = news = true;
        const ProcessOutcome& o = outcomes[i];
        if (o.ok()) {
          progress->note(fmt::format("{}: done in {:.1f} s", jobs[i].label, s.wall_seconds));
        } else {
          progress->note(fmt::format("{}: FAILED after {:.1f} s: {}", jobs[i].label, s.wall_seconds,
                                     child_failure(o, jobs[i].log_file)));
        }
      }
    }
    if (std::all_of(slots.begin(), slots.end(), [](const Slot& s) { return s.announced_end; })) break;
    const auto interval = std::chrono::duration<double>(options.status_interval_seconds);
    if (!news && changed.wait_for(lock, interval) == std::cv_status::timeout) {
      for (std::size_t i = 0; i < jobs.size(); ++i)
        if (slots[i].state == State::running) {
          const std::string latest = last_line_starting_with(jobs[i].log_file, "[");
          progress->note(fmt::format("{}: {}", jobs[i].label, latest.empty() ? std::string("starting") : latest));
        }
    }
  }
  lock.unlock();
  for (auto& t : runners) t.join();
  return outcomes;
}

}  // namespace experiments
