// Child programs side by side (experiments/io/side_by_side.hpp): they really run at once, each with its thread share
// in its environment and the rest of the parent's, a failed one does not stop the others and says why, and a
// long run is never silent.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "experiments/io/child_process.hpp"
#include "experiments/io/progress.hpp"
#include "experiments/io/side_by_side.hpp"

namespace fs = std::filesystem;
using experiments::ChildJob;
using experiments::SideBySideOptions;

namespace {

/// A fresh folder for one test's logs and files.
fs::path fresh_folder(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("tissue_side_by_side_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

ChildJob shell_job(const std::string& label, const std::string& script, const fs::path& dir) {
  return {label, {"/bin/sh", "-c", script}, (dir / (label + ".log")).string()};
}

std::string read_file(const std::string& file) {
  std::ifstream in(file);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

TEST(SideBySide, EachChildGetsItsThreadShareAndKeepsTheRestOfTheEnvironment) {
  const fs::path dir = fresh_folder("environment");
  setenv("TISSUE_SIDE_BY_SIDE_PROBE", "kept", 1);
  setenv("OMP_NUM_THREADS", "7", 1);  // the share replaces a value of the parent's
  SideBySideOptions options;
  options.threads_per_child = 3;
  experiments::Progress progress("test", 1, true);
  const auto outcomes = experiments::run_side_by_side(
      {shell_job("env", "echo \"$DEAL_II_NUM_THREADS $OMP_NUM_THREADS $OPENBLAS_NUM_THREADS $TISSUE_SIDE_BY_SIDE_PROBE\"",
                 dir)},
      options, &progress);
  unsetenv("OMP_NUM_THREADS");
  ASSERT_EQ(outcomes.size(), 1u);
  EXPECT_TRUE(outcomes[0].ok()) << outcomes[0].error;
  EXPECT_EQ(read_file((dir / "env.log").string()), "3 3 3 kept\n");
}

TEST(SideBySide, TwoChildrenRunAtOnce) {
  // Each child waits for the other's file before it writes its own and ends: one after the other, the first would
  // wait its 20 s out and fail.
  const fs::path dir = fresh_folder("at_once");
  const auto waits_for = [&](const std::string& mine, const std::string& other) {
    return "touch " + (dir / mine).string() + "; i=0; while [ ! -e " + (dir / other).string() +
           " ]; do i=$((i+1)); [ $i -gt 200 ] && exit 9; sleep 0.1; done; echo met";
  };
  SideBySideOptions options;
  experiments::Progress progress("test", 2, true);
  const auto outcomes = experiments::run_side_by_side(
      {shell_job("a", waits_for("a.ready", "b.ready"), dir), shell_job("b", waits_for("b.ready", "a.ready"), dir)},
      options, &progress);
  ASSERT_EQ(outcomes.size(), 2u);
  for (const auto& o : outcomes) EXPECT_TRUE(o.ok()) << o.error;
  EXPECT_EQ(read_file((dir / "a.log").string()), "met\n");
  EXPECT_EQ(read_file((dir / "b.log").string()), "met\n");
}

TEST(SideBySide, AFailedChildSaysWhyAndTheOthersFinish) {
  const fs::path dir = fresh_folder("failure");
  SideBySideOptions options;
  options.children = 1;  // in list order: the failure comes first and the second job still runs
  experiments::Progress progress("test", 2, true);
  const auto outcomes = experiments::run_side_by_side(
      {shell_job("bad", "echo '[compare x 1/2] solving'; echo 'error: /load/force: a non-zero force' >&2; exit 3", dir),
       shell_job("good", "echo fine", dir)},
      options, &progress);
  ASSERT_EQ(outcomes.size(), 2u);
  EXPECT_FALSE(outcomes[0].ok());
  EXPECT_EQ(outcomes[0].exit_code, 3);
  EXPECT_EQ(experiments::last_error_line((dir / "bad.log").string()), "/load/force: a non-zero force");
  EXPECT_TRUE(outcomes[1].ok()) << outcomes[1].error;
  EXPECT_EQ(read_file((dir / "good.log").string()), "fine\n");
}

TEST(SideBySide, ALongChildsLatestProgressLineIsPrinted) {
  const fs::path dir = fresh_folder("status");
  SideBySideOptions options;
  options.status_interval_seconds = 0.2;
  experiments::Progress progress("test", 1);
  testing::internal::CaptureStderr();
  const auto outcomes = experiments::run_side_by_side(
      {shell_job("long", "echo '[compare x 1/2] first'; echo '[compare x 2/2] second'; sleep 1.5", dir)}, options,
      &progress);
  const std::string printed = testing::internal::GetCapturedStderr();
  ASSERT_TRUE(outcomes[0].ok()) << outcomes[0].error;
  EXPECT_NE(printed.find("[test 1/1] long: started beside the others (1 thread; log "), std::string::npos) << printed;
  EXPECT_NE(printed.find("[test] long: [compare x 2/2] second"), std::string::npos) << printed;
  EXPECT_NE(printed.find("[test] long: done in "), std::string::npos) << printed;
}

TEST(SideBySide, TailAndThreadShare) {
  const fs::path dir = fresh_folder("tail");
  {
    std::ofstream out(dir / "log.txt");
    for (int i = 1; i <= 30; ++i) out << "line " << i << "\n";
  }
  const std::string tail = experiments::tail_of_file((dir / "log.txt").string(), 25);
  EXPECT_EQ(tail.substr(0, 7), "line 6\n");
  EXPECT_EQ(std::count(tail.begin(), tail.end(), '\n'), 25);
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  EXPECT_EQ(experiments::threads_per_child(1), cores);
  EXPECT_EQ(experiments::threads_per_child(2), std::max(1, cores / 2));
  EXPECT_EQ(experiments::threads_per_child(4 * cores), 1);
  std::string why;
  SideBySideOptions none;
  none.children = 0;
  EXPECT_FALSE(none.IsValid(&why));
  EXPECT_EQ(why, "children must be >= 1");
}
