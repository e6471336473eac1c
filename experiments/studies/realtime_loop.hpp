#pragma once
// A fixed-rate loop with deadlines (the haptic probe's 1 kHz replay, docs/SURROGATE.md §7): the schedule,
// the scheduling the loop's thread asks for and what it got, the loop itself and its statistics.
//
// Times are nanoseconds on CLOCK_MONOTONIC (MonotonicNs) inside; reports are in microseconds. Sample i of a
// loop at rate R is released at start + i/R, computed from the start each time (never by adding periods,
// which drifts); its deadline is the end of its period, the next release; the thread sleeps on an absolute
// time until `spin` before the release and spins from there (the kernel wakes a sleeper late by tens of
// microseconds, or by milliseconds when another thread holds the core; the spin absorbs the first, SCHED_FIFO
// prevents the second).
#include <time.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace experiments {

using MonotonicNs = std::int64_t;  ///< [ns] on CLOCK_MONOTONIC

MonotonicNs monotonic_now_ns();
timespec to_timespec(MonotonicNs t);  ///< for clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, ...); t >= 0

/// The release, deadline and wake-up times of a fixed-rate loop. A value; thread-safe (const only).
class DeadlineSchedule {
 public:
  /// @param start_ns release of sample 0 [ns, CLOCK_MONOTONIC]
  /// @param rate_hz samples per second, > 0 (need not divide 1e9: releases are rounded to the nearest ns
  ///                from the exact i / rate, so the error never accumulates)
  /// @param spin_ns how long before each release the sleep ends [ns], >= 0
  DeadlineSchedule(MonotonicNs start_ns, double rate_hz, MonotonicNs spin_ns);

  MonotonicNs start() const { return start_; }
  double rate() const { return rate_; }
  MonotonicNs spin() const { return spin_; }
  double period_us() const { return 1e6 / rate_; }  ///< nominal [us]

  MonotonicNs release(std::int64_t i) const;                             ///< start + round(i * 1e9 / rate)
  MonotonicNs deadline(std::int64_t i) const { return release(i + 1); }  ///< the end of sample i's period
  MonotonicNs wake(std::int64_t i) const { return release(i) - spin_; }  ///< where the sleep ends

 private:
  MonotonicNs start_, spin_;
  double rate_;
};

/// What the loop's thread asks for.
struct LoopSchedulingRequest {
  bool realtime = true;     ///< false: the normal scheduler, no pinning, no memory lock (to compare with)
  int cpu = -1;             ///< CPU to pin to; -1: the last one the process may use (sched_getaffinity)
  int priority = 50;        ///< SCHED_FIFO priority (1-99)
  bool lock_memory = true;  ///< mlockall(MCL_CURRENT | MCL_FUTURE): no page fault inside the loop
};

/// What the loop's thread got. Each refusal is one sentence saying what was refused, why (the error code) and
/// what to change; the loop goes on without it.
struct LoopScheduling {
  bool realtime_requested = false;
  std::string policy = "SCHED_OTHER";
  int priority = 0;
  int cpu = -1;                   ///< pinned CPU, -1 when not pinned
  bool cpu_explicit = false;      ///< the CPU was requested, not chosen as the last allowed one
  std::vector<int> allowed_cpus;  ///< the thread's affinity set when the pin was chosen
  bool memory_locked = false;
  bool timer_slack_set = false;  ///< PR_SET_TIMERSLACK to 1 ns (matters under SCHED_OTHER; FIFO has none)
  std::vector<std::string> refusals;

  /// One line: "SCHED_FIFO priority 50, pinned to CPU 1 (the last allowed of 0-1), memory locked, ...".
  std::string describe() const;
};

/// The CPU to pin to: `requested` if it is in `allowed`, the last of `allowed` when requested is -1. Throws
/// std::invalid_argument (naming the allowed set) when requested is not allowed or `allowed` is empty.
int choose_cpu(const std::vector<int>& allowed, int requested);

/// Record the outcome of one request in `s`: `error` is 0 when granted, else the error code the call returned
/// (pthread_* return it; for mlockall it is errno). A refusal is recorded, never thrown.
void note_pin_result(int error, int cpu, LoopScheduling* s);
void note_fifo_result(int error, int priority, LoopScheduling* s);
void note_memory_lock_result(int error, LoopScheduling* s);

/// Ask for `request` for the calling thread (pin, SCHED_FIFO, timer slack) and the process (memory lock).
/// Refusals are recorded in the result, not printed and not thrown, except an explicit request.cpu outside
/// the allowed set (std::invalid_argument). The pin and the policy last as long as the thread; the memory
/// lock is the process's: undo it with release_loop_scheduling().
LoopScheduling acquire_loop_scheduling(const LoopSchedulingRequest& request);
void release_loop_scheduling(const LoopScheduling& s);  ///< munlockall() if the memory was locked

/// One period of the loop, as measured.
struct LoopSample {
  MonotonicNs woke_late_ns = 0;  ///< end of the sleep minus its target (release - spin)
  MonotonicNs latency_ns = 0;    ///< answer minus release
  MonotonicNs compute_ns = 0;    ///< answer minus the start of the body (the body alone)
  bool missed = false;           ///< answer later than the deadline (the period's end)
};

/// Nearest-rank percentile (p in [0, 100]) of a non-empty list.
double nearest_rank_percentile(std::vector<double> v, double p);

/// The statistics a replay reports. Percentiles are nearest-rank; times in microseconds.
struct LoopSummary {
  std::size_t samples = 0, missed = 0;
  double missed_percent = 0.0;
  double latency_p50_us = 0, latency_p99_us = 0, latency_max_us = 0;
  double compute_p50_us = 0, compute_p99_us = 0, compute_max_us = 0;
  double woke_late_p50_us = 0, woke_late_p99_us = 0, woke_late_max_us = 0;
};
LoopSummary summarize(const std::vector<LoopSample>& samples);  ///< all zero for an empty list

struct FixedRateLoopOptions {
  double rate_hz = 1000.0;
  MonotonicNs spin_ns = 100'000;
  MonotonicNs lead_ns = 20'000'000;  ///< from the end of the warm-up to the first release
  LoopSchedulingRequest scheduling;
};

/// Run body(i) for i = 0 .. n-1 at the fixed rate on a new thread that asks for options.scheduling first,
/// fills `obtained`, then calls warm_up (if given; untimed: it may report `obtained` and touch the body's
/// code and data on that core), then loops. Blocks until the loop ends; an exception from body or warm_up
/// ends the loop and is rethrown here. `body` must not allocate or block if its timing is to mean anything;
/// body and warm_up run on the loop's thread only, one call at a time, and the caller's thread waits.
/// @param obtained receives the scheduling obtained (required; written before warm_up is called)
std::vector<LoopSample> run_fixed_rate_loop(std::size_t n, const FixedRateLoopOptions& options,
                                            const std::function<void(std::size_t)>& body,
                                            const std::function<void()>& warm_up, LoopScheduling* obtained);

}  // namespace experiments
