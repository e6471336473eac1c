// The fixed-rate loop of the probe's replay (experiments/studies/realtime_loop.hpp): the schedule's arithmetic, the
// statistics it reports and the reporting of refused scheduling requests. No assertion on time: speed and
// missed deadlines are measured by `tissue probe --trace` (docs/SURROGATE.md §7), never asserted here.
#include <gtest/gtest.h>

#include <cerrno>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "experiments/studies/realtime_loop.hpp"

namespace experiments {
namespace {

constexpr std::int64_t kStart = 123'456'789'012'345;  // a monotonic clock a day and a half after boot [ns]

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(DeadlineSchedule, ReleasesAreComputedFromTheStartAndDoNotDriftOverAMillionPeriods) {
  // Integer rates, for which the exact release i * 1e9 / rate rounded to the nearest ns (half up) is
  // floor((2 i 1e9 + rate) / (2 rate)) in integers: 1000 Hz divides 1e9, 3 and 7 Hz do not, 1024 Hz gives
  // exact half-ns ties.
  for (const std::int64_t rate : {1000, 3, 7, 1024}) {
    const DeadlineSchedule schedule(kStart, static_cast<double>(rate), 0);
    for (std::int64_t i = 0; i <= 1'000'000; ++i) {
      const std::int64_t exact = (2 * i * 1'000'000'000 + rate) / (2 * rate);
      ASSERT_EQ(schedule.release(i) - kStart, exact) << "rate " << rate << " Hz, sample " << i;
    }
  }
  const DeadlineSchedule khz(kStart, 1000.0, 0);
  EXPECT_EQ(khz.release(1'000'000) - kStart, 1'000'000'000'000);  // 1e6 periods of 1 ms: 1000 s, to the ns
  // What the test guards against: adding a period rounded to the ns drifts by the rounding times the count
  // (a third of a ns per period at 3 Hz: a third of a millisecond after 1e6 periods).
  const DeadlineSchedule three(kStart, 3.0, 0);
  std::int64_t accumulated = kStart;
  for (int i = 0; i < 1'000'000; ++i) accumulated += 333'333'333;
  EXPECT_EQ(three.release(1'000'000) - accumulated, 333'333);
}

TEST(DeadlineSchedule, DeadlineIsThePeriodsEndAndTheSleepEndsTheSpinBeforeTheRelease) {
  const std::int64_t spin = 100'000;
  const DeadlineSchedule schedule(kStart, 1000.0, spin);
  EXPECT_EQ(schedule.release(0), kStart);
  for (const std::int64_t i : {0, 1, 2, 999, 1'000'000}) {
    EXPECT_EQ(schedule.deadline(i), schedule.release(i + 1)) << i;
    EXPECT_EQ(schedule.deadline(i) - schedule.release(i), 1'000'000) << i;
    EXPECT_EQ(schedule.wake(i), schedule.release(i) - spin) << i;
  }
  const DeadlineSchedule no_spin(kStart, 1000.0, 0);
  EXPECT_EQ(no_spin.wake(5), no_spin.release(5));
  EXPECT_DOUBLE_EQ(schedule.period_us(), 1000.0);
  EXPECT_THROW(DeadlineSchedule(kStart, 0.0, 0), std::invalid_argument);
  EXPECT_THROW(DeadlineSchedule(kStart, -1.0, 0), std::invalid_argument);
  EXPECT_THROW(DeadlineSchedule(kStart, 1000.0, -1), std::invalid_argument);

  const timespec ts = to_timespec(1'234'567'890'123);
  EXPECT_EQ(ts.tv_sec, 1234);
  EXPECT_EQ(ts.tv_nsec, 567'890'123);
}

TEST(LoopStatistics, NearestRankPercentiles) {
  EXPECT_EQ(nearest_rank_percentile({5, 1, 3}, 50), 3);  // rank ceil(1.5) = 2 of the sorted list
  EXPECT_EQ(nearest_rank_percentile({5, 1, 3}, 0), 1);
  EXPECT_EQ(nearest_rank_percentile({5, 1, 3}, 100), 5);
  EXPECT_EQ(nearest_rank_percentile({7}, 99), 7);
  EXPECT_THROW(nearest_rank_percentile({}, 50), std::invalid_argument);
}

TEST(LoopStatistics, PercentilesMaxAndMissedOfASyntheticList) {
  // 1000 periods: latencies 1 .. 1000 us in a shuffled order, the three largest missed; the wake-up 2 us late
  // and the body half the latency.
  std::vector<LoopSample> samples(1000);
  for (int i = 0; i < 1000; ++i) {
    const int us = 1 + (i * 7919) % 1000;  // 7919 is prime to 1000: a permutation of 1 .. 1000
    samples[i].latency_ns = us * 1000;
    samples[i].compute_ns = us * 500;
    samples[i].woke_late_ns = 2000;
    samples[i].missed = us > 997;
  }
  const LoopSummary s = summarize(samples);
  EXPECT_EQ(s.samples, 1000u);
  EXPECT_DOUBLE_EQ(s.latency_p50_us, 500.0);
  EXPECT_DOUBLE_EQ(s.latency_p99_us, 990.0);
  EXPECT_DOUBLE_EQ(s.latency_max_us, 1000.0);
  EXPECT_DOUBLE_EQ(s.compute_p50_us, 250.0);
  EXPECT_DOUBLE_EQ(s.compute_p99_us, 495.0);
  EXPECT_DOUBLE_EQ(s.compute_max_us, 500.0);
  EXPECT_DOUBLE_EQ(s.woke_late_p99_us, 2.0);
  EXPECT_EQ(s.missed, 3u);
  EXPECT_DOUBLE_EQ(s.missed_percent, 0.3);

  const LoopSummary none = summarize({});
  EXPECT_EQ(none.samples, 0u);
  EXPECT_EQ(none.missed, 0u);
  EXPECT_EQ(none.missed_percent, 0.0);
}

TEST(LoopScheduling, TheLastAllowedCpuIsChosenAndAnExplicitOneIsChecked) {
  EXPECT_EQ(choose_cpu({0, 1}, -1), 1);
  EXPECT_EQ(choose_cpu({0, 2, 3}, 2), 2);
  try {
    choose_cpu({0, 2, 3}, 5);
    ADD_FAILURE() << "CPU 5 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_TRUE(contains(e.what(), "CPU 5 is not one this process may use (0,2-3)")) << e.what();
  }
  EXPECT_THROW(choose_cpu({}, -1), std::invalid_argument);
}

TEST(LoopScheduling, GrantedRequestsAreDescribed) {
  LoopScheduling s;
  s.realtime_requested = true;
  s.allowed_cpus = {0, 1};
  note_pin_result(0, 1, &s);
  note_fifo_result(0, 50, &s);
  note_memory_lock_result(0, &s);
  EXPECT_TRUE(s.refusals.empty());
  EXPECT_EQ(s.describe(), "SCHED_FIFO priority 50, pinned to CPU 1 (the last allowed of 0-1), memory locked");
  EXPECT_TRUE(contains(LoopScheduling{}.describe(), "SCHED_OTHER, not pinned, memory not locked"));
}

TEST(LoopScheduling, RefusedFifoIsReportedNotFatalAndTheLoopKeepsTheNormalScheduler) {
  // The failure codes pthread_setschedparam returns without CAP_SYS_NICE (EPERM) or for a bad priority.
  LoopScheduling s;
  s.realtime_requested = true;
  s.allowed_cpus = {0, 1};
  note_pin_result(0, 1, &s);
  EXPECT_NO_THROW(note_fifo_result(EPERM, 50, &s));
  EXPECT_EQ(s.policy, "SCHED_OTHER");
  EXPECT_EQ(s.priority, 0);
  ASSERT_EQ(s.refusals.size(), 1u);
  const std::string& why = s.refusals.front();
  EXPECT_TRUE(contains(why, "SCHED_FIFO priority 50 refused (EPERM")) << why;
  EXPECT_TRUE(contains(why, "CAP_SYS_NICE")) << why;  // what to change
  EXPECT_TRUE(contains(why, "ulimit -r")) << why;
  EXPECT_TRUE(contains(why, "normal scheduler (SCHED_OTHER)")) << why;  // what happens instead
  EXPECT_TRUE(contains(s.describe(), "SCHED_OTHER, pinned to CPU 1")) << s.describe();
  EXPECT_TRUE(contains(s.describe(), "(1 request(s) refused)")) << s.describe();

  EXPECT_NO_THROW(note_fifo_result(EINVAL, 120, &s));
  ASSERT_EQ(s.refusals.size(), 2u);
  EXPECT_TRUE(contains(s.refusals.back(), "SCHED_FIFO priority 120 refused (EINVAL")) << s.refusals.back();
}

TEST(LoopScheduling, RefusedPinAndMemoryLockAreReportedNotFatal) {
  LoopScheduling s;
  s.realtime_requested = true;
  EXPECT_NO_THROW(note_pin_result(EINVAL, 3, &s));
  EXPECT_NO_THROW(note_memory_lock_result(ENOMEM, &s));
  EXPECT_EQ(s.cpu, -1);
  EXPECT_FALSE(s.memory_locked);
  ASSERT_EQ(s.refusals.size(), 2u);
  EXPECT_TRUE(contains(s.refusals[0], "pinning the loop's thread to CPU 3 refused (EINVAL")) << s.refusals[0];
  EXPECT_TRUE(contains(s.refusals[1], "mlockall: ENOMEM")) << s.refusals[1];
  EXPECT_TRUE(contains(s.refusals[1], "ulimit -l")) << s.refusals[1];
  EXPECT_TRUE(contains(s.describe(), "not pinned, memory not locked")) << s.describe();
}

TEST(FixedRateLoop, CallsTheBodyOncePerSampleInOrderAndPropagatesItsFailure) {
  // Real scheduling calls: a refused pin or SCHED_FIFO (no CAP_SYS_NICE under CI) must end up in `obtained`,
  // not in an exception. The memory lock stays off: it would lock this whole test process.
  FixedRateLoopOptions options;
  options.rate_hz = 2000.0;
  options.spin_ns = 50'000;
  options.lead_ns = 1'000'000;
  options.scheduling.lock_memory = false;
  for (const bool realtime : {false, true}) {
    options.scheduling.realtime = realtime;
    std::vector<std::size_t> calls;
    calls.reserve(20);
    int warm_ups = 0;
    LoopScheduling obtained;
    const std::vector<LoopSample> samples = run_fixed_rate_loop(
        20, options, [&](std::size_t i) { calls.push_back(i); }, [&] { ++warm_ups; }, &obtained);
    ASSERT_EQ(samples.size(), 20u);
    ASSERT_EQ(calls.size(), 20u);
    for (std::size_t i = 0; i < calls.size(); ++i) EXPECT_EQ(calls[i], i);
    EXPECT_EQ(warm_ups, 1);
    for (const LoopSample& x : samples) {
      EXPECT_GE(x.latency_ns, x.compute_ns);  // the release comes no later than the body's start
      EXPECT_GE(x.compute_ns, 0);
      EXPECT_GE(x.woke_late_ns, 0);  // clock_nanosleep never returns before its absolute time
    }
    EXPECT_EQ(obtained.realtime_requested, realtime);
    if (realtime) {
      EXPECT_TRUE(obtained.policy == "SCHED_FIFO" || !obtained.refusals.empty()) << obtained.describe();
      EXPECT_TRUE(obtained.cpu >= 0 || !obtained.refusals.empty()) << obtained.describe();
    } else {
      EXPECT_EQ(obtained.policy, "SCHED_OTHER");
      EXPECT_EQ(obtained.cpu, -1);
      EXPECT_TRUE(obtained.refusals.empty());
    }
  }
  LoopScheduling obtained;
  options.scheduling.realtime = false;
  EXPECT_THROW(run_fixed_rate_loop(
                   5, options,
                   [](std::size_t i) {
                     if (i == 2) throw std::runtime_error("body failed");
                   },
                   nullptr, &obtained),
               std::runtime_error);
}

}  // namespace
}  // namespace experiments
