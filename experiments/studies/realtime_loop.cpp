#include "experiments/studies/realtime_loop.hpp"

#include <fmt/format.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/resource.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <exception>
#include <stdexcept>
#include <thread>
#include <utility>

namespace experiments {
namespace {

constexpr MonotonicNs kNsPerSecond = 1'000'000'000;

/// "EPERM: Operation not permitted": the symbol a user can search for, and the text.
std::string error_text(int error) {
  static const std::pair<int, const char*> names[] = {{EPERM, "EPERM"},   {EINVAL, "EINVAL"},
                                                      {ENOMEM, "ENOMEM"}, {EAGAIN, "EAGAIN"},
                                                      {ESRCH, "ESRCH"},   {EFAULT, "EFAULT"}};
  const char* name = nullptr;
  for (const auto& [code, symbol] : names)
    if (code == error) name = symbol;
  return name ? fmt::format("{}: {}", name, std::strerror(error))
              : fmt::format("error {}: {}", error, std::strerror(error));
}

/// "0-1", "0,2-5": the usual cpuset notation.
std::string cpu_list(const std::vector<int>& cpus) {
  std::string out;
  for (std::size_t i = 0; i < cpus.size();) {
    std::size_t j = i;
    while (j + 1 < cpus.size() && cpus[j + 1] == cpus[j] + 1) ++j;
    if (!out.empty()) out += ',';
    out += j == i ? fmt::format("{}", cpus[i]) : fmt::format("{}-{}", cpus[i], cpus[j]);
    i = j + 1;
  }
  return out.empty() ? "none" : out;
}

/// The soft limit of `resource` divided by `divisor`, followed by `unit`; for the refusals' "now ...".
std::string limit_text(int resource, rlim_t divisor, const char* unit) {
  rlimit l{};
  if (getrlimit(resource, &l) != 0) return "unknown";
  if (l.rlim_cur == RLIM_INFINITY) return "unlimited";
  return fmt::format("{}{}", l.rlim_cur / divisor, unit);
}

void sleep_until(MonotonicNs t) {
  const timespec ts = to_timespec(t);
  // Absolute: an interrupted sleep resumes to the same instant, and a late start does not push the wake-up.
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

inline void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();  // lets a sibling hyperthread run while this one spins
#endif
}

}  // namespace

MonotonicNs monotonic_now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<MonotonicNs>(ts.tv_sec) * kNsPerSecond + ts.tv_nsec;
}

timespec to_timespec(MonotonicNs t) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(t / kNsPerSecond);
  ts.tv_nsec = static_cast<long>(t % kNsPerSecond);
  return ts;
}

DeadlineSchedule::DeadlineSchedule(MonotonicNs start_ns, double rate_hz, MonotonicNs spin_ns)
    : start_(start_ns), spin_(spin_ns), rate_(rate_hz) {
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz))
    throw std::invalid_argument(
        fmt::format("the loop's rate must be a positive number of Hz, got {}", rate_hz));
  if (spin_ns < 0) throw std::invalid_argument(fmt::format("the spin must be >= 0 ns, got {}", spin_ns));
}

MonotonicNs DeadlineSchedule::release(std::int64_t i) const {
  // From the start every time, in long double (64-bit mantissa: exact to the ns for i * period below 2^63
  // ns): adding a rounded period i times would drift by i times its rounding.
  return start_ + static_cast<MonotonicNs>(std::llround(static_cast<long double>(i) * 1e9L / rate_));
}

std::string LoopScheduling::describe() const {
  if (!realtime_requested)
    return "normal scheduler (realtime not requested): SCHED_OTHER, not pinned, memory not locked";
  std::string out = policy;
  if (policy == "SCHED_FIFO") out += fmt::format(" priority {}", priority);
  if (cpu >= 0)
    out += cpu_explicit
               ? fmt::format(", pinned to CPU {} (as requested; allowed {})", cpu, cpu_list(allowed_cpus))
               : fmt::format(", pinned to CPU {} (the last allowed of {})", cpu, cpu_list(allowed_cpus));
  else
    out += ", not pinned";
  out += memory_locked ? ", memory locked" : ", memory not locked";
  if (timer_slack_set) out += ", timer slack 1 ns";
  if (!refusals.empty()) out += fmt::format(" ({} request(s) refused)", refusals.size());
  return out;
}

int choose_cpu(const std::vector<int>& allowed, int requested) {
  if (allowed.empty())
    throw std::invalid_argument(
        "the thread may run on no CPU (empty affinity set): check the container's cpuset");
  if (requested < 0) return *std::max_element(allowed.begin(), allowed.end());
  if (std::find(allowed.begin(), allowed.end(), requested) == allowed.end())
    throw std::invalid_argument(
        fmt::format("CPU {} is not one this process may use ({}): pick one of those, or leave the CPU to the "
                    "default (the last)",
                    requested, cpu_list(allowed)));
  return requested;
}

void note_pin_result(int error, int cpu, LoopScheduling* s) {
  if (error == 0) {
    s->cpu = cpu;
    return;
  }
  s->cpu = -1;
  s->refusals.push_back(
      fmt::format("pinning the loop's thread to CPU {} refused ({}): it may migrate between cores; check the "
                  "affinity the process was started with (taskset -p PID) and the container's cpuset",
                  cpu, error_text(error)));
}

void note_fifo_result(int error, int priority, LoopScheduling* s) {
  if (error == 0) {
    s->policy = "SCHED_FIFO";
    s->priority = priority;
    return;
  }
  s->policy = "SCHED_OTHER";
  s->priority = 0;
  const std::string consequence =
      "the loop runs under the normal scheduler (SCHED_OTHER), where other work on its core can delay a "
      "wake-up by milliseconds";
  if (error == EPERM)
    s->refusals.push_back(
        fmt::format("SCHED_FIFO priority {} refused ({}): the process needs CAP_SYS_NICE or an RLIMIT_RTPRIO "
                    "of at least {} "
                    "(`ulimit -r`, now {}); in a container add the capability (docker --cap-add=SYS_NICE), "
                    "and under cgroup "
                    "v1 give its group a non-zero cpu.rt_runtime_us; {}",
                    priority, error_text(error), priority, limit_text(RLIMIT_RTPRIO, 1, ""), consequence));
  else
    s->refusals.push_back(
        fmt::format("SCHED_FIFO priority {} refused ({}); {}", priority, error_text(error), consequence));
}

void note_memory_lock_result(int error, LoopScheduling* s) {
  if (error == 0) {
    s->memory_locked = true;
    return;
  }
  s->memory_locked = false;
  s->refusals.push_back(fmt::format(
      "locking the process's memory refused (mlockall: {}): raise RLIMIT_MEMLOCK (`ulimit -l`, now {}) or "
      "grant CAP_IPC_LOCK; without it a page fault inside the loop can delay a sample",
      error_text(error), limit_text(RLIMIT_MEMLOCK, 1024, " kB")));
}

LoopScheduling acquire_loop_scheduling(const LoopSchedulingRequest& request) {
  LoopScheduling s;
  s.realtime_requested = request.realtime;
  if (!request.realtime) return s;

  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) != 0) {
    note_pin_result(errno, request.cpu, &s);
  } else {
    for (int c = 0; c < CPU_SETSIZE; ++c)
      if (CPU_ISSET(c, &set)) s.allowed_cpus.push_back(c);
    const int cpu = choose_cpu(s.allowed_cpus, request.cpu);
    s.cpu_explicit = request.cpu >= 0;
    CPU_ZERO(&set);
    CPU_SET(cpu, &set);
    note_pin_result(pthread_setaffinity_np(pthread_self(), sizeof set, &set), cpu, &s);
  }

  sched_param p{};
  p.sched_priority = request.priority;
  note_fifo_result(pthread_setschedparam(pthread_self(), SCHED_FIFO, &p), request.priority, &s);

  // The default slack (50 us) lets the kernel defer a SCHED_OTHER sleeper's wake-up to batch timers; FIFO
  // threads have none. Set it so that the fallback keeps the sleep's precision.
  s.timer_slack_set = prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL) == 0;

  if (request.lock_memory) note_memory_lock_result(mlockall(MCL_CURRENT | MCL_FUTURE) == 0 ? 0 : errno, &s);
  return s;
}

void release_loop_scheduling(const LoopScheduling& s) {
  if (s.memory_locked) munlockall();
}

double nearest_rank_percentile(std::vector<double> v, double p) {
  if (v.empty()) throw std::invalid_argument("percentile of an empty list");
  std::sort(v.begin(), v.end());
  const std::size_t rank = static_cast<std::size_t>(std::ceil(p / 100.0 * static_cast<double>(v.size())));
  return v[std::clamp<std::size_t>(rank, 1, v.size()) - 1];
}

LoopSummary summarize(const std::vector<LoopSample>& samples) {
  LoopSummary s;
  s.samples = samples.size();
  if (samples.empty()) return s;
  std::vector<double> latency, compute, late;
  for (const LoopSample& x : samples) {
    latency.push_back(1e-3 * static_cast<double>(x.latency_ns));
    compute.push_back(1e-3 * static_cast<double>(x.compute_ns));
    late.push_back(1e-3 * static_cast<double>(x.woke_late_ns));
    s.missed += x.missed;
  }
  s.missed_percent = 100.0 * static_cast<double>(s.missed) / static_cast<double>(s.samples);
  s.latency_p50_us = nearest_rank_percentile(latency, 50);
  s.latency_p99_us = nearest_rank_percentile(latency, 99);
  s.latency_max_us = *std::max_element(latency.begin(), latency.end());
  s.compute_p50_us = nearest_rank_percentile(compute, 50);
  s.compute_p99_us = nearest_rank_percentile(compute, 99);
  s.compute_max_us = *std::max_element(compute.begin(), compute.end());
  s.woke_late_p50_us = nearest_rank_percentile(late, 50);
  s.woke_late_p99_us = nearest_rank_percentile(late, 99);
  s.woke_late_max_us = *std::max_element(late.begin(), late.end());
  return s;
}

std::vector<LoopSample> run_fixed_rate_loop(std::size_t n, const FixedRateLoopOptions& options,
                                            const std::function<void(std::size_t)>& body,
                                            const std::function<void()>& warm_up, LoopScheduling* obtained) {
  if (!obtained) throw std::invalid_argument("run_fixed_rate_loop: `obtained` is required");
  // Allocated here, before the loop's thread locks memory and starts: the loop only writes into it.
  std::vector<LoopSample> samples(n);
  std::exception_ptr failure;
  // Its own thread: the pin and the policy end with it, and the caller's thread keeps its scheduling.
  std::thread loop([&] {
    LoopScheduling scheduling;
    try {
      scheduling = acquire_loop_scheduling(options.scheduling);
      *obtained = scheduling;
      if (warm_up) warm_up();
      const DeadlineSchedule schedule(monotonic_now_ns() + options.lead_ns, options.rate_hz, options.spin_ns);
      for (std::size_t i = 0; i < n; ++i) {
        const auto k = static_cast<std::int64_t>(i);
        const MonotonicNs wake = schedule.wake(k), release = schedule.release(k);
        sleep_until(wake);
        MonotonicNs now = monotonic_now_ns();
        LoopSample& x = samples[i];
        x.woke_late_ns = now - wake;
        while (now < release) {
          cpu_relax();
          now = monotonic_now_ns();
        }
        body(i);
        const MonotonicNs done = monotonic_now_ns();
        x.latency_ns = done - release;
        x.compute_ns = done - now;
        x.missed = done > schedule.deadline(k);
      }
    } catch (...) {
      failure = std::current_exception();
    }
    release_loop_scheduling(scheduling);
  });
  loop.join();
  if (failure) std::rethrow_exception(failure);
  return samples;
}

}  // namespace experiments
