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

  std::string write_sweep(const json& parameters, const json& set = json(), const json& compare = json()) {
    json doc = {{"name", "test_sweep"}, {"base_case", "configs/base.json"}, {"parameters", parameters}};
    if (!set.is_null()) doc["set"] = set;
    if (!compare.is_null()) doc["compare"] = compare;
    const fs::path p = dir_ / "sweep.json";
    std::ofstream(p) << doc.dump(2);
    return p.string();
  }

  /// A stand-in `tissue verify fem` result: a mesh study of lung_small_ci at 24 and 18 mm with extrapolated samples.
  void write_study(const fs::path& path, const std::string& case_name = "lung_small_ci") {
    fs::create_directories(path.parent_path());
    const json level24 = {{"mesh_size_mm", 24.0}}, level18 = {{"mesh_size_mm", 18.0}};
    const json study = {{"mesh_convergence",
                         {{case_name,
                           {{"levels", {level24, level18}},
                            {"richardson", {{"extrapolated_sample_displacements_mm", {{1.0, 0.0, 0.0}}}}}}}}}};
    std::ofstream(path) << study.dump(2);
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
  // The reference's own RMSE against the extrapolated samples: 0.05 mm at an 18 mm FEM mesh, none (solved) else.
  const bool coarse_fem = run.document["geometry"]["mesh_size"].get<double>() == 18.0;
  o.summary = {{"n_samples", 10},
               {"flagged_samples", json::array({1})},
               {"geometry_seconds", 1.0},
               {"reference",
                {{"peak_sample_displacement_mm", 3.5},
                 {"timings", {{"total_seconds", 2.0}}},
                 {"samples", coarse_fem ? "extrapolated" : "solved"},
                 {"solved_minus_extrapolated_rms_mm", coarse_fem ? json(0.05) : json(nullptr)}}},
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

TEST_F(Sweep, RunsOfAnStlCaseFindItsSurfaceFromTheirOwnFolder) {
  // configs/lung_stl.json names its STL relative to itself. A run's case is written to OUT/cases/, so the path must
  // reach it from there: absolute, also when the sweep file is named relative to the working directory.
  json lobe = json::parse(std::ifstream(std::string(TISSUE_TEST_CONFIG_DIR) + "/lung_stl.json"));
  lobe["geometry"]["stl_file"] = "surfaces/lobe.stl";
  fs::create_directories(dir_ / "configs" / "surfaces");
  std::ofstream(dir_ / "configs" / "surfaces" / "lobe.stl") << "solid lobe\nendsolid lobe\n";
  std::ofstream(dir_ / "configs" / "lobe.json") << lobe.dump(2);
  std::ofstream(dir_ / "sweep.json") << json{{"name", "stl_sweep"},
                                            {"base_case", "configs/lobe.json"},
                                            {"parameters", {{{"pointer", "/material/k"}, {"values", {0, 1}}}}}}
                                            .dump(2);
  const fs::path before = fs::current_path();
  fs::current_path(dir_);
  const auto runs = experiments::expand_sweep(experiments::load_sweep("sweep.json"));
  fs::current_path(before);
  ASSERT_EQ(runs.size(), 2u);
  for (const auto& r : runs) {
    const fs::path stl = r.document["geometry"]["stl_file"].get<std::string>();
    EXPECT_TRUE(stl.is_absolute()) << stl;
    EXPECT_TRUE(fs::equivalent(stl, dir_ / "configs" / "surfaces" / "lobe.stl")) << stl;
  }
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

TEST_F(Sweep, ZippedPointersTakeTheirValuesTogetherOneColumnEach) {
  const std::string file = write_sweep(
      json::array({{{"pointers", {"/geometry/mesh_size", "/meshless/node_spacing"}}, {"values", {{24, 16}, {18, 12}}}},
                   {{"pointer", "/material/k"}, {"values", {0, 1}}}}));
  const auto spec = experiments::load_sweep(file);
  ASSERT_EQ(spec.parameters.size(), 2u);
  EXPECT_TRUE(spec.parameters[0].zipped);
  EXPECT_EQ(spec.columns(), (std::vector<std::string>{"/geometry/mesh_size", "/meshless/node_spacing", "/material/k"}));
  const auto runs = experiments::expand_sweep(spec);
  ASSERT_EQ(runs.size(), 4u);  // 2 pairs x 2 values, not 2 x 2 x 2
  // One value per column, the zipped pair together; the last parameter varies fastest.
  EXPECT_EQ(runs[0].values, (std::vector<json>{24, 16, 0}));
  EXPECT_EQ(runs[1].values, (std::vector<json>{24, 16, 1}));
  EXPECT_EQ(runs[2].values, (std::vector<json>{18, 12, 0}));
  EXPECT_EQ(runs[3].document["geometry"]["mesh_size"], 18);
  EXPECT_EQ(runs[3].document["meshless"]["node_spacing"], 12);
  EXPECT_EQ(runs[3].document["material"]["k"], 1);
  // The runs.csv header has one column per pointer, in order, after run_id and status.
  const auto header = experiments::runs_csv_header(spec);
  EXPECT_EQ(std::vector<std::string>(header.begin(), header.begin() + 5),
            (std::vector<std::string>{"run_id", "status", "/geometry/mesh_size", "/meshless/node_spacing",
                                      "/material/k"}));
  std::atomic<int> calls{0};
  const auto report = experiments::run_sweep(
      spec, runs, options(),
      [&](const experiments::SweepRun& run, const std::string&, const std::string&, const std::string&) {
        return fake_compare(run, &calls);
      });
  EXPECT_EQ(report.succeeded, 4);
  const auto lines = csv_lines();
  ASSERT_EQ(lines.size(), 5u);
  EXPECT_NE(lines[3].find(",ok,18,12,0,10,1,3.5,,0.12,"), std::string::npos) << lines[3];
}

TEST_F(Sweep, BadZippedParametersAreRejectedNamingThePointerOrValue) {
  const json both = {"/geometry/mesh_size", "/meshless/node_spacing"};
  std::string m = error_of(write_sweep(
      json::array({{{"pointer", "/material/k"}, {"pointers", both}, {"values", {{24, 16}}}}})));
  EXPECT_NE(m.find("sweep.json: /parameters/0/pointers: expected either \"pointer\" (one) or \"pointers\" (several, "
                   "zipped), not both"),
            std::string::npos)
      << m;
  m = error_of(write_sweep(json::array({{{"values", {{24, 16}}}}})));
  EXPECT_NE(m.find("sweep.json: /parameters/0: expected \"pointer\" (one JSON pointer) or \"pointers\" (several "
                   "that vary together)"),
            std::string::npos)
      << m;
  m = error_of(write_sweep(json::array({{{"pointers", json::array()}, {"values", {{24, 16}}}}})));
  EXPECT_NE(m.find("sweep.json: /parameters/0/pointers: expected a non-empty array of JSON pointers"),
            std::string::npos)
      << m;
  m = error_of(write_sweep(json::array({{{"pointers", {"/geometry/mesh_size", 3}}, {"values", {{24, 16}}}}})));
  EXPECT_NE(m.find("sweep.json: /parameters/0/pointers/1: expected a JSON pointer string, got number"),
            std::string::npos)
      << m;
  m = error_of(write_sweep(json::array({{{"pointers", {"/geometry/mesh_size", "meshless/node_spacing"}},
                                         {"values", {{24, 16}}}}})));
  EXPECT_NE(m.find("sweep.json: /parameters/0/pointers/1: expected an RFC 6901 JSON pointer"), std::string::npos)
      << m;
  // A value that is not an array of one value per pointer.
  m = error_of(write_sweep(json::array({{{"pointers", both}, {"values", {{24, 16}, {18, 12, 10}}}}})));
  EXPECT_NE(m.find("sweep.json: /parameters/0/values/1: expected an array of 2 values, one for each of "
                   "/geometry/mesh_size, /meshless/node_spacing (in that order), got an array of 3"),
            std::string::npos)
      << m;
  m = error_of(write_sweep(json::array({{{"pointers", both}, {"values", {18}}}})));
  EXPECT_NE(m.find("sweep.json: /parameters/0/values/0: expected an array of 2 values, one for each of "
                   "/geometry/mesh_size, /meshless/node_spacing (in that order), got number"),
            std::string::npos)
      << m;
  // A bad value is named down to its pointer's place in the pair.
  m = error_of(write_sweep(json::array({{{"pointers", both}, {"values", {{24, 16}, {18, -5}}}}})));
  EXPECT_NE(m.find("sweep.json: /parameters/0/values/1/1: /meshless/node_spacing = -5 makes an invalid case: "),
            std::string::npos)
      << m;
  EXPECT_NE(m.find("/meshless/node_spacing: expected a number in [0.5, 200]"), std::string::npos) << m;
  // A pointer in a zipped parameter and in another parameter (or twice in one), or also in /set.
  m = error_of(write_sweep(json::array({{{"pointers", both}, {"values", {{24, 16}}}},
                                        {{"pointer", "/meshless/node_spacing"}, {"values", {12}}}})));
  EXPECT_NE(m.find("sweep.json: /parameters/1/pointer: /meshless/node_spacing is swept twice"), std::string::npos)
      << m;
  m = error_of(write_sweep(json::array({{{"pointers", {"/material/k", "/material/k"}}, {"values", {{1, 2}}}}})));
  EXPECT_NE(m.find("sweep.json: /parameters/0/pointers/1: /material/k is swept twice"), std::string::npos) << m;
  m = error_of(write_sweep(json::array({{{"pointers", both}, {"values", {{24, 16}}}}}), {{"/geometry/mesh_size", 20}}));
  EXPECT_NE(m.find("sweep.json: /parameters/0/pointers/0: /geometry/mesh_size is also in /set"), std::string::npos)
      << m;
  m = error_of(write_sweep(json::array({{{"pointers", both}, {"value", {{24, 16}}}}})));
  EXPECT_NE(m.find("sweep.json: /parameters/0/value: unknown key; allowed keys here are: pointer (one), pointers"),
            std::string::npos)
      << m;
}

TEST_F(Sweep, CompareOptionsArePassedToEveryRunAndCheckedBeforeAnyRun) {
  write_study(dir_ / "verify" / "fem.json");
  const json zipped = json::array(
      {{{"pointers", {"/geometry/mesh_size", "/meshless/node_spacing"}}, {"values", {{24, 16}, {18, 12}}}}});
  // The study's path is relative to the sweep file's folder, and made absolute for the runs.
  auto spec = experiments::load_sweep(
      write_sweep(zipped, json(), {{"reference", "extrapolated"}, {"reference_error", "verify/fem.json"}}));
  const std::string study = fs::absolute(dir_ / "verify" / "fem.json").lexically_normal().string();
  EXPECT_EQ(spec.compare.reference_error, study);
  EXPECT_EQ(spec.compare.arguments(),
            (std::vector<std::string>{"--reference", "extrapolated", "--reference-error", study}));
  const auto runs = experiments::expand_sweep(spec);
  ASSERT_EQ(runs.size(), 2u);
  // The compare options change the results, so the same case without them is another run.
  const auto plain = experiments::expand_sweep(experiments::load_sweep(write_sweep(zipped)));
  EXPECT_NE(plain[0].id, runs[0].id);
  EXPECT_TRUE(experiments::SweepCompareOptions{}.arguments().empty());

  // Refusals, each before anything runs, naming the sweep file and the JSON path in it.
  std::string m = error_of(write_sweep(zipped, json(), {{"reference", "extrapolated"}, {"reference_error", "nope.json"}}));
  EXPECT_NE(m.find("sweep.json: /compare/reference_error: expected an existing `tissue verify fem` result (fem.json), "
                   "but \"" + (dir_ / "nope.json").string() + "\" cannot be opened"),
            std::string::npos)
      << m;
  std::ofstream(dir_ / "not_a_study.json") << "{\"cantilever\": {}}";
  m = error_of(write_sweep(zipped, json(), {{"reference_error", "not_a_study.json"}}));
  EXPECT_NE(m.find("sweep.json: /compare/reference_error: expected a `tissue verify fem` result with a mesh_convergence "
                   "study"),
            std::string::npos)
      << m;
  m = error_of(write_sweep(zipped, json(), {{"reference", "extrapolated"}}));
  EXPECT_NE(m.find("sweep.json: /compare: \"reference\": \"extrapolated\" needs \"reference_error\""), std::string::npos)
      << m;
  m = error_of(write_sweep(zipped, json(), {{"reference", "richardson"}, {"reference_error", "verify/fem.json"}}));
  EXPECT_NE(m.find("sweep.json: /compare/reference: expected \"solved\" or \"extrapolated\", got \"richardson\""),
            std::string::npos)
      << m;
  m = error_of(write_sweep(zipped, json(), {{"reference_errors", "verify/fem.json"}}));
  EXPECT_NE(m.find("sweep.json: /compare/reference_errors: unknown key; allowed keys here are: reference, "
                   "reference_error"),
            std::string::npos)
      << m;
  // The extrapolated samples exist only at the study's levels: a 12 mm FEM would be refused by every compare.
  m = error_of(write_sweep(
      json::array({{{"pointers", {"/geometry/mesh_size", "/meshless/node_spacing"}}, {"values", {{24, 16}, {12, 12}}}}}),
      json(), {{"reference", "extrapolated"}, {"reference_error", "verify/fem.json"}}));
  EXPECT_NE(m.find("sweep.json: /compare/reference_error: the run /geometry/mesh_size = 12, /meshless/node_spacing = 12 "
                   "has /geometry/mesh_size = 12 mm, which is not a level of the mesh study of lung_small_ci in " +
                   study + " (levels 24, 18 mm)"),
            std::string::npos)
      << m;
  write_study(dir_ / "verify" / "other.json", "lung_large_ci");
  m = error_of(write_sweep(zipped, json(), {{"reference", "extrapolated"}, {"reference_error", "verify/other.json"}}));
  EXPECT_NE(m.find("sweep.json: /compare/reference_error: " + (dir_ / "verify" / "other.json").string() +
                   " holds no mesh study of the case \"lung_small_ci\""),
            std::string::npos)
      << m;
  // With the solved reference any mesh size goes (the study only gives the error bar).
  EXPECT_EQ(error_of(write_sweep(
                json::array({{{"pointer", "/geometry/mesh_size"}, {"values", {12}}}}), json(),
                {{"reference", "solved"}, {"reference_error", "verify/fem.json"}})),
            "no error");
}

TEST_F(Sweep, FemRmseAgainstTheExtrapolatedSamplesIsAColumnEmptyWhenSolved) {
  write_study(dir_ / "verify" / "fem.json");
  const auto spec = experiments::load_sweep(write_sweep(
      json::array({{{"pointers", {"/geometry/mesh_size", "/meshless/node_spacing"}}, {"values", {{24, 16}, {18, 12}}}}}),
      {{"/compare", {{"models", {"enrichment"}}}}}, {{"reference", "solved"}, {"reference_error", "verify/fem.json"}}));
  const auto header = experiments::runs_csv_header(spec);
  // The models of /compare as /set leaves it give the model columns: enrichment only.
  EXPECT_EQ(std::count(header.begin(), header.end(), "visibility_rmse_mm"), 0);
  EXPECT_EQ(std::count(header.begin(), header.end(), "enrichment_rmse_mm"), 1);
  ASSERT_GE(header.size(), 3u);
  EXPECT_EQ(header[header.size() - 3], "fem_rmse_vs_extrapolated_mm");
  std::atomic<int> calls{0};
  experiments::run_sweep(spec, experiments::expand_sweep(spec), options(),
                         [&](const experiments::SweepRun& run, const std::string&, const std::string&,
                             const std::string&) { return fake_compare(run, &calls); });
  const auto lines = csv_lines();
  ASSERT_EQ(lines.size(), 3u);
  const auto field_before_wall_seconds = [](const std::string& line) {
    const std::size_t last = line.rfind(',');               // before error
    const std::size_t wall = line.rfind(',', last - 1);     // before wall_seconds
    const std::size_t fem = line.rfind(',', wall - 1);      // before fem_rmse_vs_extrapolated_mm
    return line.substr(fem + 1, wall - fem - 1);
  };
  EXPECT_EQ(field_before_wall_seconds(lines[1]), "") << lines[1];  // 24 mm: the solved reference
  EXPECT_EQ(field_before_wall_seconds(lines[2]), "0.05") << lines[2];
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

  // The sweep's compare options reach the child's command line.
  std::ofstream(fake) << "#!/bin/sh\nmkdir -p \"$4\"\necho \"$@\" > \"$4/argv.txt\"\n"
                         "echo '{\"n_samples\": 10, \"flagged_samples\": []}' > \"$4/summary.json\"\n";
  fs::remove_all(dir_ / "out");
  report = experiments::run_sweep(
      spec, experiments::expand_sweep(spec), options(),
      experiments::compare_in_child_process(fake.string(), false, {"--reference", "extrapolated"}));
  EXPECT_EQ(report.succeeded, 1);
  std::ifstream argv_in(dir_ / "out" / "runs" / experiments::expand_sweep(spec)[0].id / "argv.txt");
  std::string argv_line;
  std::getline(argv_in, argv_line);
  EXPECT_NE(argv_line.find("compare "), std::string::npos) << argv_line;
  EXPECT_NE(argv_line.find(" --no-plot --reference extrapolated"), std::string::npos) << argv_line;

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
