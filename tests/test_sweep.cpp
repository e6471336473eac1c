// `tissue sweep`: the Cartesian product of JSON-pointer parameters, validated before anything runs (errors name
// the sweep file, the parameter and the value), resumable runs.csv rows appended whole, failed runs recorded
// while the sweep goes on, parallel workers. The runs here are stand-ins (a function), so the tests take
// seconds; the real `tissue compare` runs in the accuracy gates.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "core/case_error.hpp"
#include "experiments/comparator/compare.hpp"
#include "experiments/studies/sweep.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

class Sweep : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / (std::string("tissue_sweep_") + info->name() + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "configs");
    fs::copy_file(std::string(TISSUE_TEST_CONFIG_DIR) + "/ci/lung_small_ci.json", dir_ / "configs" / "base.json");
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write_sweep(const json& parameters, const json& set = json()) {
    json doc = {{"name", "test_sweep"}, {"base_case", "configs/base.json"}, {"parameters", parameters}};
    if (!set.is_null()) doc["set"] = set;
    const fs::path p = dir_ / "sweep.json";
    std::ofstream(p) << doc.dump(2);
    return p.string();
  }

  std::string error_of(const std::string& sweep_file) {
    try {
      experiments::expand_sweep(experiments::load_sweep(sweep_file));
    } catch (const core::CaseError& e) {
      return e.what();
    }
    return "no error";
  }

  std::vector<std::string> csv_lines() const {
    std::ifstream in(dir_ / "out" / "runs.csv");
    std::vector<std::string> lines;
    std::string line;
    while (std::getline(in, line)) lines.push_back(line);
    return lines;
  }

  experiments::SweepOptions options(int workers = 1) const {
    experiments::SweepOptions o;
    o.out_dir = (dir_ / "out").string();
    o.workers = workers;
    return o;
  }

  fs::path dir_;
};

/// A stand-in for `tissue compare`: a summary whose enrichment RMSE is the node spacing / 100 mm; node spacing
/// 13 fails.
experiments::RunOutcome fake_compare(const experiments::SweepRun& run, std::atomic<int>* calls) {
  ++*calls;
  experiments::RunOutcome o;
  const double h = run.document["meshless"]["node_spacing"].get<double>();
  if (h == 13.0) {
    o.error = "node spacing 13 is unlucky, with a comma and \"quotes\"\nand a line break";
    return o;
  }
  o.ok = true;
  o.summary = {{"n_samples", 10},
               {"flagged_samples", json::array({1})},
               {"geometry_seconds", 1.0},
               {"reference", {{"peak_sample_displacement_mm", 3.5}, {"timings", {{"total_seconds", 2.0}}}}},
               {"models",
                {{"enrichment", {{"rmse_mm", h / 100}, {"timings", {{"total_seconds", 3.0}}}}},
                 {"visibility", {{"rmse_mm", h / 50}, {"timings", {{"total_seconds", 3.0}}}}}}}};
  return o;
}

TEST_F(Sweep, CartesianProductWithSetValuesAndStableIds) {
  const std::string file = write_sweep(
      json::array({{{"pointer", "/meshless/node_spacing"}, {"values", {20, 16}}},
                   {{"pointer", "/material/k"}, {"values", {0, 0.5, 1}}}}),
      {{"/time/steps", 2}});
  const auto spec = experiments::load_sweep(file);
  const auto runs = experiments::expand_sweep(spec);
  ASSERT_EQ(runs.size(), 6u);
  // The last parameter varies fastest.
  EXPECT_EQ(runs[0].values, (std::vector<json>{20, 0}));
  EXPECT_EQ(runs[1].values, (std::vector<json>{20, 0.5}));
  EXPECT_EQ(runs[3].values, (std::vector<json>{16, 0}));
  EXPECT_EQ(runs[4].document["material"]["k"], 0.5);
  EXPECT_EQ(runs[4].document["meshless"]["node_spacing"], 16);
  for (const auto& r : runs) EXPECT_EQ(r.document["time"]["steps"], 2);
  std::set<std::string> ids;
  for (const auto& r : runs) {
    EXPECT_EQ(r.id.size(), 16u);
    ids.insert(r.id);
  }
  EXPECT_EQ(ids.size(), 6u);
  EXPECT_EQ(experiments::expand_sweep(spec)[5].id, runs[5].id);  // the id is a function of the case alone
  // A value equal to the base is one run, not two.
  const auto same = experiments::expand_sweep(experiments::load_sweep(
      write_sweep(json::array({{{"pointer", "/material/k"}, {"values", {1, 1}}}}))));
  EXPECT_EQ(same.size(), 1u);
}

TEST_F(Sweep, BadPointersAndValuesAreRejectedNamingTheFileParameterAndValue) {
  std::string m = error_of(write_sweep(json::array({{{"pointer", "meshless/node_spacing"}, {"values", {10}}}})));
  EXPECT_NE(m.find("sweep.json: /parameters/0/pointer: expected an RFC 6901 JSON pointer"), std::string::npos) << m;
  m = error_of(write_sweep(json::array({{{"pointer", "/meshles/node_spacing"}, {"values", {10}}}})));
  EXPECT_NE(m.find("/parameters/0/pointer: /meshles/node_spacing does not exist in the base case (its parent "
                   "/meshles is missing)"),
            std::string::npos)
      << m;
  // A key the schema does not know: core::parse_case names it.
  m = error_of(write_sweep(json::array({{{"pointer", "/meshless/node_spacin"}, {"values", {10}}}})));
  EXPECT_NE(m.find("sweep.json: /parameters/0/values/0: /meshless/node_spacin = 10 makes an invalid case"),
            std::string::npos)
      << m;
  EXPECT_NE(m.find("unknown key"), std::string::npos) << m;
  // An out-of-range value, second in its list.
  m = error_of(write_sweep(json::array({{{"pointer", "/material/k"}, {"values", {0.5}}},
                                        {{"pointer", "/meshless/node_spacing"}, {"values", {16, -5}}}})));
  EXPECT_NE(m.find("sweep.json: /parameters/1/values/1: /meshless/node_spacing = -5 makes an invalid case: "),
            std::string::npos)
      << m;
  EXPECT_NE(m.find("/meshless/node_spacing: expected a number in [0.5, 200]"), std::string::npos) << m;
  m = error_of(write_sweep(json::array({{{"pointer", "/load/force/3"}, {"values", {1}}}})));
  EXPECT_NE(m.find("past the end of the array /load/force"), std::string::npos) << m;
  m = error_of(write_sweep(json::array({{{"pointer", "/material/k"}, {"values", json::array()}}})));
  EXPECT_NE(m.find("/parameters/0/values: expected a non-empty array"), std::string::npos) << m;
  m = error_of(write_sweep(json::array({{{"pointer", "/material/k"}, {"values", {1}}},
                                        {{"pointer", "/material/k"}, {"values", {2}}}})));
  EXPECT_NE(m.find("swept twice"), std::string::npos) << m;
  m = error_of(write_sweep(json::array({{{"pointer", "/material/k"}, {"values", {1}}}}), {{"/material/nu", 0.7}}));
  EXPECT_NE(m.find("sweep.json: /set: the base case"), std::string::npos) << m;
}

TEST_F(Sweep, CommandRejectsABadSweepBeforeRunningAnything) {
  const std::string file = write_sweep(json::array({{{"pointer", "/meshless/node_spacing"}, {"values", {16, "x"}}}}));
  const fs::path out = dir_ / "results" / "s";
  FILE* pipe = popen((std::string(TISSUE_BINARY) + " sweep " + file + " --out " + out.string() + " 2>&1").c_str(), "r");
  std::string output;
  std::array<char, 4096> buffer{};
  while (fgets(buffer.data(), buffer.size(), pipe)) output += buffer.data();
  EXPECT_EQ(WEXITSTATUS(pclose(pipe)), 2) << output;
  EXPECT_NE(output.find("sweep.json: /parameters/0/values/1: /meshless/node_spacing = x makes an invalid case"),
            std::string::npos)
      << output;
  EXPECT_FALSE(fs::exists(dir_ / "results")) << "nothing may be written before the sweep is valid";
}

TEST_F(Sweep, FailedRunIsRecordedTheSweepGoesOnAndARerunSkipsFinishedRuns) {
  const auto spec = experiments::load_sweep(
      write_sweep(json::array({{{"pointer", "/meshless/node_spacing"}, {"values", {20, 13, 16}}}})));
  const auto runs = experiments::expand_sweep(spec);
  std::atomic<int> calls{0};
  const auto fn = [&](const experiments::SweepRun& run, const std::string& case_file, const std::string&,
                      const std::string&) {
    // The generated case is written before the run, and is what the run reads.
    std::ifstream in(case_file);
    EXPECT_EQ(json::parse(in), run.document);
    return fake_compare(run, &calls);
  };
  auto report = experiments::run_sweep(spec, runs, options(), fn);
  EXPECT_EQ(report.total, 3);
  EXPECT_EQ(report.succeeded, 2);
  EXPECT_EQ(report.failed, 1);
  EXPECT_EQ(calls, 3);
  auto lines = csv_lines();
  ASSERT_EQ(lines.size(), 4u);
  const auto header = experiments::runs_csv_header(spec);
  EXPECT_EQ(lines[0].substr(0, 37), "run_id,status,/meshless/node_spacing,");
  EXPECT_EQ(header.back(), "error");
  EXPECT_EQ(lines[1].substr(0, 16), runs[0].id);
  EXPECT_NE(lines[1].find(",ok,20,10,1,3.5,,0.2,"), std::string::npos) << lines[1];
  // The error is quoted, its quotes doubled, its line break a space: the row stays one line.
  EXPECT_NE(lines[2].find(",failed,13,"), std::string::npos) << lines[2];
  EXPECT_NE(lines[2].find("\"node spacing 13 is unlucky, with a comma and \"\"quotes\"\" and a line break\""),
            std::string::npos)
      << lines[2];

  // Rerun: the two finished runs are skipped, the failed one is tried again.
  report = experiments::run_sweep(spec, runs, options(), fn);
  EXPECT_EQ(report.skipped, 2);
  EXPECT_EQ(report.failed, 1);
  EXPECT_EQ(calls, 4);
  EXPECT_EQ(csv_lines().size(), 5u);
  auto no_retry = options();
  no_retry.retry_failed = false;
  report = experiments::run_sweep(spec, runs, no_retry, fn);
  EXPECT_EQ(report.skipped, 3);
  EXPECT_EQ(calls, 4);
}

TEST_F(Sweep, HalfWrittenRowIsRemovedAndThatRunReruns) {
  const auto spec = experiments::load_sweep(
      write_sweep(json::array({{{"pointer", "/meshless/node_spacing"}, {"values", {20, 16}}}})));
  const auto runs = experiments::expand_sweep(spec);
  std::atomic<int> calls{0};
  const auto fn = [&](const experiments::SweepRun& run, const std::string&, const std::string&, const std::string&) {
    return fake_compare(run, &calls);
  };
  experiments::run_sweep(spec, runs, options(), fn);
  // Simulate a crash in the middle of appending the second row.
  auto lines = csv_lines();
  ASSERT_EQ(lines.size(), 3u);
  {
    std::ofstream out(dir_ / "out" / "runs.csv", std::ios::trunc);
    out << lines[0] << "\n" << lines[1] << "\n" << lines[2].substr(0, 30);
  }
  experiments::RunsCsv csv((dir_ / "out" / "runs.csv").string(), experiments::runs_csv_header(spec));
  EXPECT_TRUE(csv.repaired());
  EXPECT_EQ(csv.last_status(runs[0].id), "ok");
  EXPECT_EQ(csv.last_status(runs[1].id), "");
  const auto report = experiments::run_sweep(spec, runs, options(), fn);
  EXPECT_EQ(report.skipped, 1);
  EXPECT_EQ(report.succeeded, 1);
  lines = csv_lines();
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines[2].substr(0, 16), runs[1].id);
}

TEST_F(Sweep, RunsCsvOfAnotherSweepIsRefused) {
  const auto spec = experiments::load_sweep(write_sweep(json::array({{{"pointer", "/material/k"}, {"values", {0}}}})));
  fs::create_directories(dir_ / "out");
  std::ofstream(dir_ / "out" / "runs.csv") << "run_id,status,/meshless/node_spacing\n";
  std::atomic<int> calls{0};
  try {
    experiments::run_sweep(spec, experiments::expand_sweep(spec), options(),
                           [&](const experiments::SweepRun& run, const std::string&, const std::string&,
                               const std::string&) { return fake_compare(run, &calls); });
    ADD_FAILURE() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("belongs to another sweep"), std::string::npos) << e.what();
  }
  EXPECT_EQ(calls, 0);
}

TEST_F(Sweep, ParallelWorkersAppendEveryRowOnceAndWhole) {
  const auto spec = experiments::load_sweep(write_sweep(
      json::array({{{"pointer", "/meshless/node_spacing"}, {"values", {10, 12, 14, 16, 18, 20, 22, 24}}}})));
  const auto runs = experiments::expand_sweep(spec);
  std::atomic<int> calls{0}, running{0}, max_running{0};
  const auto fn = [&](const experiments::SweepRun& run, const std::string&, const std::string&, const std::string&) {
    const int now = ++running;
    int seen = max_running.load();
    while (now > seen && !max_running.compare_exchange_weak(seen, now)) {
    }
    usleep(50000);
    --running;
    return fake_compare(run, &calls);
  };
  const auto report = experiments::run_sweep(spec, runs, options(3), fn);
  EXPECT_EQ(report.succeeded, 8);
  EXPECT_EQ(max_running, 3);
  const auto lines = csv_lines();
  ASSERT_EQ(lines.size(), 9u);
  std::set<std::string> ids;
  const std::size_t columns = experiments::runs_csv_header(spec).size();
  for (std::size_t i = 1; i < lines.size(); ++i) {
    ids.insert(lines[i].substr(0, 16));
    EXPECT_EQ(static_cast<std::size_t>(std::count(lines[i].begin(), lines[i].end(), ',')), columns - 1) << lines[i];
  }
  EXPECT_EQ(ids.size(), 8u);
}

TEST_F(Sweep, ChildProcessRunsRecordTheirSummaryOrTheirError) {
  // A stand-in program with the `tissue compare CASE --out DIR` interface writes a summary.json ...
  const fs::path fake = dir_ / "fake_tissue.sh";
  std::ofstream(fake) << "#!/bin/sh\nmkdir -p \"$4\"\necho 'progress line'\n"
                         "echo '{\"n_samples\": 10, \"flagged_samples\": [], \"models\": {\"enrichment\": "
                         "{\"rmse_mm\": 0.25}, \"visibility\": {\"rmse_mm\": 0.5}}}' > \"$4/summary.json\"\n";
  fs::permissions(fake, fs::perms::owner_all);
  auto spec = experiments::load_sweep(write_sweep(json::array({{{"pointer", "/material/k"}, {"values", {0.5}}}})));
  auto report = experiments::run_sweep(spec, experiments::expand_sweep(spec), options(),
                                       experiments::compare_in_child_process(fake.string(), false));
  EXPECT_EQ(report.succeeded, 1);
  auto lines = csv_lines();
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_NE(lines[1].find(",ok,0.5,10,0,,,0.25,,,0.5,"), std::string::npos) << lines[1];

  // ... and the real program's error line is recorded when the case fails after validation (the load point is
  // 220 mm off the lung: a geometry check, seconds into the run).
  spec = experiments::load_sweep(
      write_sweep(json::array({{{"pointer", "/load/point"}, {"values", {{-300.0, 0.0, 20.0}}}}})));
  fs::remove_all(dir_ / "out");
  report = experiments::run_sweep(spec, experiments::expand_sweep(spec), options(),
                                  experiments::compare_in_child_process(TISSUE_BINARY, false));
  EXPECT_EQ(report.failed, 1);
  lines = csv_lines();
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_NE(lines[1].find(",failed,\"[-300.0,0.0,20.0]\","), std::string::npos) << lines[1];
  EXPECT_NE(lines[1].find("/load/point: the load point is"), std::string::npos) << lines[1];
  EXPECT_NE(lines[1].find("(" + std::string(TISSUE_BINARY) + " exited with status 2)"), std::string::npos) << lines[1];
  EXPECT_FALSE(fs::exists(dir_ / "out" / "runs" / (experiments::expand_sweep(spec)[0].id)));
}

TEST(CsvField, QuotesOnlyWhenNeeded) {
  EXPECT_EQ(experiments::csv_field("plain"), "plain");
  EXPECT_EQ(experiments::csv_field("[0.3,0,0]"), "\"[0.3,0,0]\"");
  EXPECT_EQ(experiments::csv_field("say \"hi\""), "\"say \"\"hi\"\"\"");
  EXPECT_EQ(experiments::csv_field("two\nlines"), "two lines");
}

}  // namespace
