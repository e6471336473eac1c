// `tissue reproduce --jobs 2` runs Table 1's cases side by side, each `tissue compare` a child process with one
// thread: its Table 1 must be the one that the cases give one after the other in the reproduce process (--jobs 1),
// which would not hold if the children were handed other compare options (the reference's error bar, the cut effect).
// With the timing too, the timing's surrogate is trained beside the cases by `tissue fit` and read from its file: it
// must answer as the one trained in the reproduce process.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

const std::string kConfigDir = TISSUE_TEST_CONFIG_DIR;

json read_json(const fs::path& file) {
  std::ifstream in(file);
  return json::parse(in);
}

std::string read_text(const fs::path& file) {
  std::ifstream in(file);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Run `tissue reproduce` on `plan` (no plots; Table 1 only unless `with_timing`) with `jobs` into `out`; returns its
/// exit code.
int reproduce(const fs::path& plan, int jobs, const fs::path& out, bool with_timing = false) {
  const std::string command = std::string(TISSUE_BINARY) + " reproduce --plan " + plan.string() +
                              (with_timing ? "" : " --table1-only") + " --no-plot --jobs " + std::to_string(jobs) +
                              " --out " + out.string() + " > " + out.string() + ".log 2>&1";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// `a` and `b` equal to `relative` of their size. The runs differ in their thread counts, so in the order of some
/// sums: on 2 cores (two threads against one) the RMSEs and cut effects agreed to 2.2e-14 relative. 1e-9 leaves room
/// for a Newton iteration more or less on a machine with other thread counts (the Newton residuals stop near 1e-9).
void expect_close(const json& a, const json& b, const std::string& what, double relative = 1e-9) {
  ASSERT_TRUE(a.is_number() && b.is_number()) << what << ": " << a << " against " << b;
  EXPECT_NEAR(a.get<double>(), b.get<double>(), relative * std::max(1e-12, std::abs(a.get<double>()))) << what;
}

}  // namespace

TEST(ReproduceSideBySide, Table1IsTheSameAsOneCaseAfterTheOther) {
  const fs::path dir = fs::temp_directory_path() / "tissue_reproduce_side_by_side";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path plan = dir / "plan.json";
  std::ofstream(plan) << json{{"table1",
                               {{{"label", "small"},
                                 {"config", kConfigDir + "/ci/lung_small_ci.json"},
                                 {"paper", {{"enrichment_mm", 1.05}, {"visibility_mm", 4.01}}}},
                                {{"label", "cutting"},
                                 {"config", kConfigDir + "/ci/lung_large_ci.json"},
                                 {"paper", {{"enrichment_mm", 4.04}, {"visibility_mm", 8.03}}}}}},
                              {"timing", {{"config", kConfigDir + "/ci/lung_small_ci.json"}, {"forces_N", {0.1}}}}}
                                 .dump(2);
  ASSERT_EQ(reproduce(plan, 1, dir / "one_after_the_other"), 0) << read_text(dir / "one_after_the_other.log");
  ASSERT_EQ(reproduce(plan, 2, dir / "side_by_side"), 0) << read_text(dir / "side_by_side.log");

  const std::string log = read_text(dir / "side_by_side.log");
  EXPECT_NE(log.find("Table 1, cutting: started beside the others ("), std::string::npos) << log;
  const json sequential = read_json(dir / "one_after_the_other/table1.json").at("rows");
  const json side = read_json(dir / "side_by_side/table1.json").at("rows");
  ASSERT_EQ(sequential.size(), 2u);
  ASSERT_EQ(side.size(), 2u);
  for (std::size_t r = 0; r < 2; ++r) {
    const json& a = sequential[r];
    const json& b = side[r];
    const std::string label = a.at("label");
    EXPECT_FALSE(a.contains("run")) << label;
    const int threads = std::max(1, static_cast<int>(std::thread::hardware_concurrency()) / 2);
    EXPECT_EQ(b.at("run").get<std::string>(), "side by side, 2 at once with " + std::to_string(threads) +
                                                  (threads == 1 ? " thread each" : " threads each"));
    expect_close(a.at("peak_reference_mm"), b.at("peak_reference_mm"), label + " peak");
    ASSERT_EQ(a.at("models").size(), b.at("models").size()) << label;
    for (std::size_t m = 0; m < a.at("models").size(); ++m) {
      const json& ma = a.at("models")[m];
      const json& mb = b.at("models")[m];
      EXPECT_EQ(ma.at("name"), mb.at("name"));
      expect_close(ma.at("rmse_mm"), mb.at("rmse_mm"), label + " " + ma.at("name").get<std::string>() + " RMSE");
    }
    // The error bar's study and its size: the children were given the reference's study as the parent would use it.
    EXPECT_EQ(a.at("reference_error_bar").value("known", false), b.at("reference_error_bar").value("known", false));
    EXPECT_EQ(a.at("reference_error_bar").value("source", std::string()),
              b.at("reference_error_bar").value("source", std::string()))
        << label;
    if (a.at("reference_error_bar").value("known", false))
      expect_close(a.at("reference_error_bar").at("rms_mm"), b.at("reference_error_bar").at("rms_mm"), label + " bar");
    EXPECT_EQ(a.at("cut_effect").is_null(), b.at("cut_effect").is_null()) << label;
  }
  // The cut case's own effect was solved (its uncut solves) in the child as in the parent.
  ASSERT_TRUE(side[1].at("cut_effect").is_object());
  expect_close(sequential[1].at("cut_effect").at("models").at("enrichment").at("rmse_mm"),
               side[1].at("cut_effect").at("models").at("enrichment").at("rmse_mm"), "cut effect");
  const std::string md = read_text(dir / "side_by_side/table1.md");
  EXPECT_NE(md.find("The cases ran side by side, 2 at once"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir / "side_by_side/small.log")) << "a succeeded child's log is removed";
}

TEST(ReproduceSideBySide, TheSurrogateTrainedBesideTable1AnswersAsOneTrainedAfterIt) {
  // The smallest plan with a surrogate: configs/lung_surrogate.json (20 mm cloud, 2 steps) as both Table 1 cases, the
  // timing case and the surrogate's case. About 35 s per run on 2 cores.
  const fs::path dir = fs::temp_directory_path() / "tissue_reproduce_surrogate_beside";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string config = kConfigDir + "/lung_surrogate.json";
  const json paper = {{"enrichment_mm", 1.05}, {"visibility_mm", 4.01}};
  const fs::path plan = dir / "plan.json";
  std::ofstream(plan) << json{{"table1",
                               {{{"label", "first"}, {"config", config}, {"paper", paper}},
                                {{"label", "second"}, {"config", config}, {"paper", paper}}}},
                              {"timing",
                               {{"config", config}, {"forces_N", {0.1}}, {"models", {"enrichment"}},
                                {"surrogate", config}}}}
                                 .dump(2);
  ASSERT_EQ(reproduce(plan, 1, dir / "after", true), 0) << read_text(dir / "after.log");
  ASSERT_EQ(reproduce(plan, 2, dir / "beside", true), 0) << read_text(dir / "beside.log");

  const std::string log = read_text(dir / "beside.log");
  EXPECT_NE(log.find("the timing's surrogate: tissue fit: started beside the others"), std::string::npos) << log;
  const json after = read_json(dir / "after/timing.json").at("surrogate");
  const json beside = read_json(dir / "beside/timing.json").at("surrogate");
  ASSERT_EQ(after.at("status"), "measured") << after;
  ASSERT_EQ(beside.at("status"), "measured") << beside;
  EXPECT_NE(beside.at("trained").get<std::string>().find("tissue fit"), std::string::npos);
  EXPECT_NE(after.at("trained").get<std::string>().find("here"), std::string::npos);
  EXPECT_EQ(beside.at("training_solves"), 18);  // 6 directions x 1 contact x 3 levels
  EXPECT_EQ(after.at("training_solves"), 18);
  EXPECT_GT(beside.at("training_seconds").get<double>(), 0.0);
  // The same answer: the contact displacement at each force (measured 5e-11 relative apart; one thread against two
  // changes the order of some sums).
  ASSERT_EQ(after.at("rows").size(), beside.at("rows").size());
  for (std::size_t i = 0; i < after.at("rows").size(); ++i)
    expect_close(after.at("rows")[i].at("contact_displacement_mm"), beside.at("rows")[i].at("contact_displacement_mm"),
                 "contact displacement", 1e-8);
  EXPECT_TRUE(fs::exists(dir / "beside/surrogate.json")) << "the trained file is kept with the results";
  EXPECT_FALSE(fs::exists(dir / "after/surrogate.json"));
  EXPECT_FALSE(fs::exists(dir / "beside/surrogate_fit.log")) << "a succeeded child's log is removed";
  EXPECT_NE(read_text(dir / "beside/timing.md").find("by `tissue fit` at one thread while Table 1 ran"),
            std::string::npos);
}
