// `tissue reproduce`: the plan file is checked before anything runs, and the shipped plan is the paper's.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <algorithm>
#include <nlohmann/json.hpp>

#include "core/case.hpp"
#include "core/case_error.hpp"
#include "experiments/comparator/compare.hpp"
#include "experiments/studies/cloud_change.hpp"
#include "experiments/studies/reproduce.hpp"

namespace {

const std::string kConfigDir = TISSUE_TEST_CONFIG_DIR;

/// Write `text` as a plan in the configs folder's sibling temp folder and return its path.
std::string write_plan(const std::string& name, const std::string& text) {
  const auto dir = std::filesystem::temp_directory_path() / "tissue_reproduce_plans";
  std::filesystem::create_directories(dir);
  const auto path = dir / (name + ".json");
  std::ofstream(path) << text;
  return path.string();
}

std::string error_of(const std::string& plan) {
  try {
    experiments::load_reproduce_plan(plan);
  } catch (const core::CaseError& e) {
    return e.what();
  }
  return "no error";
}

std::string plan_text(const std::string& config, const std::string& forces, const std::string& second_label) {
  return "{\"table1\": [{\"label\": \"small\", \"config\": \"" + config +
         "\", \"paper\": {\"enrichment_mm\": 1.05, \"visibility_mm\": 4.01}}, {\"label\": \"" + second_label +
         "\", \"config\": \"" + config + "\", \"paper\": {\"enrichment_mm\": 4.04, \"visibility_mm\": 8.03}}], "
         "\"timing\": {\"config\": \"" + config + "\", \"forces_N\": " + forces + "}}";
}

}  // namespace

TEST(ReproducePlan, ShippedPlanIsThePapersTable1AndFig9) {
  const experiments::ReproducePlan plan = experiments::load_reproduce_plan(kConfigDir + "/reproduce.json");
  ASSERT_EQ(plan.table1.size(), 2u);
  EXPECT_DOUBLE_EQ(plan.table1[0].paper_enrichment_mm, 1.05);  // paper Table 1, small deformation
  EXPECT_DOUBLE_EQ(plan.table1[0].paper_visibility_mm, 4.01);
  EXPECT_DOUBLE_EQ(plan.table1[1].paper_enrichment_mm, 4.04);  // cutting
  EXPECT_DOUBLE_EQ(plan.table1[1].paper_visibility_mm, 8.03);
  EXPECT_TRUE(std::filesystem::exists(plan.table1[1].config)) << plan.table1[1].config;
  // The cut row's verdict takes the meshless cloud change from the three kept sweeps over its node cloud (12, 10 and
  // 8 mm with the slope floor; 9 and 9.5 mm; 10.5 and 11 mm with the floor), each of which holds kept runs.
  ASSERT_EQ(plan.table1[1].cloud_studies.size(), 3u);
  for (const std::string& study : plan.table1[1].cloud_studies)
    EXPECT_TRUE(std::filesystem::is_directory(study + "/runs")) << study;
  // Both rows read their error bar from the one-rate family of their own problem, three meshes per level (the
  // studies named beside each other), whose means converge at an order in the band.
  for (const auto& row : plan.table1) {
    ASSERT_EQ(row.reference_family.size(), 2u) << row.label;
    for (const std::string& study : row.reference_family) EXPECT_TRUE(std::filesystem::exists(study)) << study;
  }
  // Fig. 9: 8 groups of forces within 0-4 N at one stressed point.
  ASSERT_EQ(plan.timing.forces.size(), 8u);
  for (double f : plan.timing.forces) {
    EXPECT_GT(f, 0.0);
    EXPECT_LE(f, 4.0);
  }
  // The surrogate column: a case trained at the stressed point, over the forces' range.
  ASSERT_FALSE(plan.timing.surrogate_config.empty());
  const core::Case trained = core::load_case(plan.timing.surrogate_config);
  const core::Case stressed = core::load_case(plan.timing.config);
  EXPECT_EQ((trained.surrogate.contact_points.at(0) - stressed.load.point).norm(), 0.0);
  EXPECT_LE(*std::max_element(plan.timing.forces.begin(), plan.timing.forces.end()), trained.surrogate.max_force);
  // Fig. 9 times the proposed model against LRPIM (the paper's comparison), beside the FEM reference.
  EXPECT_EQ(plan.timing.models, (std::vector<std::string>{"enrichment", "lrpim"}));
  // Table 1 has an LRPIM column: the small-deformation case runs it, the cut case says it cannot.
  for (const auto& row : plan.table1) {
    const auto& models = core::load_case(row.config).compare.models;
    EXPECT_NE(std::find(models.begin(), models.end(), "lrpim"), models.end()) << row.config;
  }
}

// A Table 1 row keeps a model that could not solve its case, with its role and reason (the LRPIM on the cut case).
// The row once iterated over a temporary copy of not_solved after its end, and README command 1 stopped with
// "cannot use at() with null" on the first plan whose case listed such a model.
TEST(ReproducePlan, Table1RowKeepsAModelThatCannotSolveTheCase) {
  const nlohmann::json summary = {
      {"models",
       {{"enrichment",
         {{"role", "proposed: the EFG"}, {"rmse_mm", 0.1021}, {"rmse_relative_to_peak", 0.0103},
          {"rmse_unflagged_mm", 0.0950}, {"timings", {{"total_seconds", 201.0}}}}}}},
      {"not_solved",
       {{"lrpim", {{"role", "Fig. 9 baseline: LRPIM"}, {"why", "the LRPIM model has no treatment of a cut"}}},
        {"visibility", {{"role", "baseline: the EFG with the visibility criterion"}, {"why", "failed: Newton"}}}}},
      {"reference", {{"model", "fem"}, {"peak_sample_displacement_mm", 9.9079}, {"error_bar", {{"known", false}}}}},
      {"flagged_samples", nlohmann::json::array()}};
  experiments::ReproducePlan::Table1Case t;
  t.label = "cutting";
  const nlohmann::json row = experiments::table1_row(t, summary);
  ASSERT_EQ(row.at("models").size(), 3u) << row.dump();
  EXPECT_EQ(row["models"][0]["name"], "enrichment");
  EXPECT_DOUBLE_EQ(row["models"][0]["seconds"].get<double>(), 201.0);
  EXPECT_EQ(row["models"][1]["name"], "lrpim");
  EXPECT_EQ(row["models"][1]["role"], "Fig. 9 baseline: LRPIM");
  EXPECT_EQ(row["models"][1]["not_solved"], "the LRPIM model has no treatment of a cut");
  EXPECT_EQ(row["models"][2]["name"], "visibility");
  EXPECT_EQ(row["models"][2]["not_solved"], "failed: Newton");
  EXPECT_EQ(experiments::table1_verdict(row), "no proposed model and baseline to compare");
  EXPECT_TRUE(row["versus_extrapolated"].is_null());  // no mesh study: Table 1's cell is "–"

  // With a study that extrapolated the reference, the row keeps every model's RMSE against it, their bar and the
  // solved reference's own distance from them (which the summary keeps under "reference").
  nlohmann::json studied = summary;
  studied["reference"]["solved_minus_extrapolated_rms_mm"] = 0.0700;
  studied["versus_extrapolated"] = {{"error_bar_mm", 0.0122}, {"models", {{"enrichment", {{"rmse_mm", 0.1210}}}}}};
  const nlohmann::json converged = experiments::table1_row(t, studied).at("versus_extrapolated");
  EXPECT_DOUBLE_EQ(converged.at("solved_reference_rmse_mm").get<double>(), 0.0700);
  EXPECT_DOUBLE_EQ(converged.at("error_bar_mm").get<double>(), 0.0122);
  EXPECT_DOUBLE_EQ(converged.at("models").at("enrichment").at("rmse_mm").get<double>(), 0.1210);
}

TEST(ReproducePlan, ASurrogateCaseTrainedElsewhereIsRefused) {
  const std::string lung = std::filesystem::absolute(kConfigDir + "/lung_small.json").string();
  // configs/lung_surrogate.json with its contact point moved 30 mm from lung_small's load point
  nlohmann::json elsewhere = nlohmann::json::parse(std::ifstream(kConfigDir + "/lung_surrogate.json"));
  elsewhere["surrogate"]["contact_points"] = {{-78.0, 30.0, 20.0}};
  const std::string surrogate_case = write_plan("surrogate_case_elsewhere", elsewhere.dump());
  std::string text = plan_text(lung, "[0.1]", "large");
  text.insert(text.size() - 2, ", \"surrogate\": \"" + surrogate_case + "\"");  // inside /timing
  const std::string error = error_of(write_plan("surrogate_elsewhere", text));
  EXPECT_NE(error.find("/timing/surrogate"), std::string::npos) << error;
  EXPECT_NE(error.find("contact_points include the timing case's load point"), std::string::npos) << error;
}

TEST(ReproducePlan, BadPlansNameTheFileAndTheJsonPath) {
  const std::string lung = std::filesystem::absolute(kConfigDir + "/lung_small.json").string();
  const std::string missing = write_plan("missing", plan_text("no_such_case.json", "[1.0]", "large"));
  EXPECT_NE(error_of(missing).find("/table1/0/config"), std::string::npos) << error_of(missing);
  EXPECT_NE(error_of(missing).find("missing.json"), std::string::npos) << error_of(missing);

  const std::string bad_force = write_plan("bad_force", plan_text(lung, "[1.0, 2.0, -0.5]", "large"));
  EXPECT_NE(error_of(bad_force).find("/timing/forces_N/2"), std::string::npos) << error_of(bad_force);

  const std::string twice = write_plan("twice", plan_text(lung, "[1.0]", "small"));
  EXPECT_NE(error_of(twice).find("/table1/1/label"), std::string::npos) << error_of(twice);

  std::string no_folder = plan_text(lung, "[1.0]", "large");
  no_folder.insert(no_folder.find("}}") + 1, ", \"cloud_studies\": [\"a\", 3]");  // in /table1/0
  const std::string cloud = error_of(write_plan("cloud", no_folder));
  EXPECT_NE(cloud.find("/table1/0/cloud_studies/1"), std::string::npos) << cloud;

  std::string no_study = plan_text(lung, "[1.0]", "large");
  no_study.insert(no_study.find("}}") + 1, ", \"reference_family\": [\"no_such_study.json\"]");  // in /table1/0
  const std::string family = error_of(write_plan("family", no_study));
  EXPECT_NE(family.find("/table1/0/reference_family/0"), std::string::npos) << family;
  EXPECT_NE(family.find("no_such_study.json does not exist"), std::string::npos) << family;

  std::string unknown_model = plan_text(lung, "[1.0]", "large");
  unknown_model.insert(unknown_model.size() - 2, ", \"models\": [\"enrichment\", \"lrpm\"]");  // inside /timing
  const std::string model = error_of(write_plan("unknown_model", unknown_model));
  EXPECT_NE(model.find("/timing/models/1"), std::string::npos) << model;
  EXPECT_NE(model.find("a registered model (fem, enrichment"), std::string::npos) << model;

  std::string reference_timed = plan_text(lung, "[1.0]", "large");
  reference_timed.insert(reference_timed.size() - 2, ", \"models\": [\"enrichment\", \"fem\"]");  // inside /timing
  const std::string reference = error_of(write_plan("reference_timed", reference_timed));
  EXPECT_NE(reference.find("reference_timed.json"), std::string::npos) << reference;
  EXPECT_NE(reference.find("/timing/models/1"), std::string::npos) << reference;
  EXPECT_NE(reference.find("a model other than the timing case's reference \"fem\""), std::string::npos) << reference;

  std::string twice_timed = plan_text(lung, "[1.0]", "large");
  twice_timed.insert(twice_timed.size() - 2, ", \"models\": [\"lrpim\", \"lrpim\"]");
  const std::string listed_twice = error_of(write_plan("twice_timed", twice_timed));
  EXPECT_NE(listed_twice.find("/timing/models/1"), std::string::npos) << listed_twice;
  EXPECT_NE(listed_twice.find("listed twice"), std::string::npos) << listed_twice;

  const std::string not_json = write_plan("not_json", "{\"table1\": [");
  EXPECT_NE(error_of(not_json).find("valid JSON"), std::string::npos) << error_of(not_json);
}

namespace {

/// A comparison summary.json of a sweep run on another node cloud: the reference's peak and each model's RMSE [mm]
/// (a negative RMSE: the model did not solve).
void write_run(const std::filesystem::path& study, const std::string& id, double peak, double enrichment,
               double visibility) {
  nlohmann::json s = {{"reference", {{"peak_sample_displacement_mm", peak}}},
                      {"models", nlohmann::json::object()},
                      {"not_solved", nlohmann::json::object()}};
  for (const auto& [name, rmse] : {std::pair<std::string, double>{"enrichment", enrichment}, {"visibility", visibility}})
    if (rmse >= 0.0)
      s["models"][name] = {{"rmse_mm", rmse}, {"details", {{"n_nodes", 5420}}}};
    else
      s["not_solved"][name] = {{"why", "failed: strain beyond the law's range"}};
  std::filesystem::create_directories(study / "runs" / id);
  std::ofstream(study / "runs" / id / "summary.json") << s.dump();
}

}  // namespace

// The cloud change of Table 1's cut row: the change of the difference where another cloud solved both variants, else
// the largest change of one variant's RMSE; runs against another reference are never mixed in.
// The Fig. 9 table: a model set up once per cloud shows its time as `= set-up once + solve`, and the ratios are given of
// the full times and of the solves alone; a model whose set-up failed shows why in every row.
TEST(TimingTable, ShowsTheSetUpOnceAndBothRatios) {
  const nlohmann::json timing = {
      {"config", "ci/lung_small_ci.json"},
      {"steps", 1},
      {"geometry_seconds", 2.5},
      {"models",
       {{{"name", "fem"}, {"role", "reference"}},
        {{"name", "enrichment"}, {"role", "proposed: the EFG"}},
        {{"name", "lrpim"}, {"role", "Fig. 9 baseline: LRPIM"}, {"setup_once_seconds", 12.0}},
        {{"name", "broken"}, {"role", "baseline"}}}},
      {"surrogate", {{"status", "not measured: the plan's /timing has no surrogate case"}}},
      {"rows",
       {{{"force_N", 0.1},
         {"models",
          {{"fem", {{"seconds", 4.0}, {"solve_seconds", 3.9}, {"setup_seconds", 0.1}, {"setup_once", false},
                    {"newton_iterations", 3}, {"peak_sample_mm", 1.5}}},
           {"enrichment", {{"seconds", 3.0}, {"solve_seconds", 2.5}, {"setup_seconds", 0.5}, {"setup_once", false},
                           {"newton_iterations", 6}, {"peak_sample_mm", 1.4}}},
           {"lrpim", {{"seconds", 18.0}, {"solve_seconds", 6.0}, {"setup_seconds", 12.0}, {"setup_once", true},
                      {"newton_iterations", 7}, {"peak_sample_mm", 1.45}}},
           {"broken", {{"error", "set-up: singular"}}}}}}}}};
  const std::string md = experiments::timing_md(timing);
  EXPECT_NE(md.find("| 18.00 s = 12.00 s set-up once + 6.00 s (7 Newton, peak 1.450 mm) |"), std::string::npos) << md;
  EXPECT_NE(md.find("| 3.00 s (6 Newton, peak 1.400 mm) |"), std::string::npos) << md;
  EXPECT_NE(md.find("| lrpim / enrichment | lrpim / enrichment, solves |"), std::string::npos) << md;
  // enrichment / fem 0.75; lrpim / enrichment 6.00 in full and 2.40 in solves; the failed model's ratios are dashes.
  EXPECT_NE(md.find("| 0.75 | 6.00 | 2.40 | – | – |"), std::string::npos) << md;
  EXPECT_NE(md.find("| failed: set-up: singular |"), std::string::npos) << md;
}

TEST(CloudChange, TakesTheDifferenceWhereBothSolvedElseOneModelsRmse) {
  const auto root = std::filesystem::temp_directory_path() / "tissue_cloud_change";
  std::filesystem::remove_all(root);
  const experiments::CloudChangeBaseline row{"enrichment", "visibility", 0.1021, 0.1439, 9.9079};
  // Only the baseline solves on the other cloud: |0.2430 - 0.1439| = 0.0991 mm.
  write_run(root / "a", "run1", 9.9079, -1.0, 0.2430);
  write_run(root / "a", "run2", 9.5, 0.3, 0.3);  // another reference: unused
  experiments::CloudChange c = experiments::cloud_change({(root / "a").string()}, row);
  ASSERT_TRUE(c.known) << c.why_unknown;
  EXPECT_NEAR(c.mm, 0.0991, 1e-12);
  EXPECT_EQ(c.measure, "one model's RMSE");
  ASSERT_EQ(c.runs.size(), 2u);
  EXPECT_EQ(c.runs[0]["enrichment"]["not_solved"], "failed: strain beyond the law's range");
  EXPECT_NE(c.runs[1]["unused"].get<std::string>().find("another reference"), std::string::npos) << c.runs.dump();
  // A second study where both solve: the difference moves from -0.0418 to -0.0300 mm, a change of 0.0118 mm.
  write_run(root / "b", "run3", 9.9079, 0.1100, 0.1400);
  c = experiments::cloud_change({(root / "a").string(), (root / "b").string()}, row);
  ASSERT_TRUE(c.known);
  EXPECT_NEAR(c.mm, 0.0118, 1e-12);
  EXPECT_EQ(c.measure, "difference");
  // No study, or a folder without runs: unknown, with what to run.
  EXPECT_FALSE(experiments::cloud_change({}, row).known);
  const experiments::CloudChange none = experiments::cloud_change({(root / "none").string()}, row);
  EXPECT_FALSE(none.known);
  EXPECT_NE(none.why_unknown.find("tissue sweep"), std::string::npos) << none.why_unknown;
}

// Against the extrapolated samples, the clouds' RMSEs are read from their summaries' versus_extrapolated; a run
// written before compare wrote them is unused, and says why.
TEST(CloudChange, AgainstTheExtrapolatedFemReadsTheRunsRmsesAgainstIt) {
  const auto root = std::filesystem::temp_directory_path() / "tissue_cloud_change_extrapolated";
  std::filesystem::remove_all(root);
  experiments::CloudChangeBaseline row{"enrichment", "visibility", 0.1210, 0.1265, 9.8187};
  row.versus_extrapolated = true;
  row.extrapolated_bar_mm = 0.0122;
  write_run(root / "a", "old", 9.8187, 0.0670, 0.1652);  // no versus_extrapolated
  write_run(root / "a", "new", 9.8187, 0.0670, 0.1652);
  write_run(root / "a", "other_study", 9.8187, 0.0670, 0.1652);
  const auto with_extrapolated = [&](const std::string& run, double bar_mm, double p_mm, double b_mm) {
    const auto summary = root / "a" / "runs" / run / "summary.json";
    nlohmann::json s = nlohmann::json::parse(std::ifstream(summary));
    s["versus_extrapolated"] = {{"error_bar_mm", bar_mm},
                                {"models", {{"enrichment", {{"rmse_mm", p_mm}}}, {"visibility", {{"rmse_mm", b_mm}}}}}};
    std::ofstream(summary) << s.dump();
  };
  with_extrapolated("new", 0.0122, 0.0900, 0.1100);
  // Scored against another study's extrapolation (another bar): its -0.1 mm difference must not count.
  with_extrapolated("other_study", 0.0096, 0.0100, 0.1100);
  const experiments::CloudChange c = experiments::cloud_change({(root / "a").string()}, row);
  ASSERT_TRUE(c.known) << c.why_unknown;
  // The difference moves from -0.0055 to -0.0200 mm (not from the solved reference's RMSEs, -0.0982).
  EXPECT_NEAR(c.mm, 0.0145, 1e-12);
  EXPECT_EQ(c.measure, "difference");
  ASSERT_EQ(c.runs.size(), 3u);
  EXPECT_EQ(c.runs[0]["enrichment"]["rmse_mm"], 0.0900);  // "new" sorts before "old" and "other_study"
  EXPECT_NE(c.runs[1]["unused"].get<std::string>().find("no RMSEs against the extrapolated FEM"), std::string::npos)
      << c.runs.dump();
  EXPECT_NE(c.runs[2]["unused"].get<std::string>().find("another mesh study's extrapolated samples"), std::string::npos)
      << c.runs.dump();
}

// The verdict sets the difference against sqrt(bar^2 + cloud change^2): 0.0418 / hypot(0.071, 0.0991) = 0.34.
TEST(CloudChange, VerdictCombinesTheReferenceBarAndTheCloudChange) {
  nlohmann::json row = {
      {"models", {{{"name", "enrichment"}, {"role", "proposed: the paper's model"}, {"rmse_mm", 0.1021}},
                  {{"name", "visibility"}, {"role", "baseline: the visibility criterion"}, {"rmse_mm", 0.1439}}}},
      {"difference_mm", -0.0418},
      {"cut_effect", nullptr},
      {"reference_error_bar", {{"known", true}, {"rms_mm", 0.071}}}};
  EXPECT_EQ(experiments::table1_verdict(row),
            "enrichment closer; the difference is 0.6× the reference's bar (the cloud change is not measured): not "
            "significant");
  row["cloud_change"] = {{"known", true}, {"mm", 0.0991}, {"measure", "one model's RMSE"}};
  EXPECT_EQ(experiments::table1_verdict(row),
            "enrichment closer; the difference is 0.3× the reference's bar and the cloud change combined: not "
            "significant");
  row["reference_error_bar"]["rms_mm"] = 0.01;
  row["cloud_change"]["mm"] = 0.01;  // 0.0418 / 0.01414 = 2.96
  EXPECT_NE(experiments::table1_verdict(row).find("3.0× the reference's bar and the cloud change combined: significant"),
            std::string::npos)
      << experiments::table1_verdict(row);
  // Against the extrapolated FEM (lung_large's figures of 29 Nov 2026): 0.1210 - 0.1265 = -0.0055 mm against
  // hypot(0.0122, 0.01) = 0.0158 mm: 0.3×.
  row["versus_extrapolated"] = {{"error_bar_mm", 0.0122},
                                {"models", {{"enrichment", {{"rmse_mm", 0.1210}}}, {"visibility", {{"rmse_mm", 0.1265}}}}}};
  // Without the clouds' RMSEs against the extrapolated samples, the change against the solved reference stands in.
  EXPECT_NE(experiments::table1_verdict(row).find("; against the extrapolated FEM enrichment closer by 0.0055 mm, 0.3× "
                                                  "their bar and the cloud change against the solved reference "
                                                  "combined: not significant"),
            std::string::npos)
      << experiments::table1_verdict(row);
  row["versus_extrapolated"]["models"]["visibility"]["rmse_mm"] = 0.0810;  // the baseline closer: 0.04 / 0.0158 = 2.5
  EXPECT_NE(experiments::table1_verdict(row).find("against the extrapolated FEM visibility closer by 0.0400 mm, 2.5× "
                                                  "their bar and the cloud change against the solved reference "
                                                  "combined: significant"),
            std::string::npos)
      << experiments::table1_verdict(row);
  // Table 1's lung_large of 30 Nov 2026: 0.0040 mm against hypot(0.0096, 0.1068) = 0.1072 mm is 0.037, which keeps
  // two decimals ("0.0×" would read as no difference).
  nlohmann::json small = row;
  small["reference_error_bar"]["rms_mm"] = 0.071;
  small["cloud_change"]["mm"] = 0.1068;
  small["versus_extrapolated"] = {{"error_bar_mm", 0.0096},
                                  {"models", {{"enrichment", {{"rmse_mm", 0.1211}}}, {"visibility", {{"rmse_mm", 0.1251}}}}}};
  EXPECT_NE(experiments::table1_verdict(small).find("enrichment closer by 0.0040 mm, 0.04× their bar"), std::string::npos)
      << experiments::table1_verdict(small);
  // With them: 0.04 / hypot(0.0122, 0.03) = 1.2.
  row["cloud_change_versus_extrapolated"] = {{"known", true}, {"mm", 0.03}, {"measure", "difference"}};
  EXPECT_NE(experiments::table1_verdict(row).find("against the extrapolated FEM visibility closer by 0.0400 mm, 1.2× "
                                                  "their bar and the cloud change against them combined: marginal"),
            std::string::npos)
      << experiments::table1_verdict(row);
}

// table1.md from rows as `reproduce` writes them: the cut row with its RMSEs against the extrapolated FEM, both cloud
// changes and their footnotes; the small row without a study ("–") and with a model that was not solved.
TEST(ReproducePlan, Table1MarkdownShowsTheConvergedFemColumnAndBothCloudChanges) {
  const nlohmann::json enrichment = {{"name", "enrichment"}, {"role", "proposed: the EFG"}, {"rmse_mm", 0.1021},
                                     {"relative", 0.0103}, {"unflagged_mm", 0.0948}};
  const nlohmann::json visibility = {{"name", "visibility"}, {"role", "baseline: visibility"}, {"rmse_mm", 0.1439},
                                     {"relative", 0.0145}, {"unflagged_mm", 0.0806}};
  nlohmann::json cut = {
      {"label", "cutting"},
      {"models", {enrichment, visibility}},
      {"difference_mm", -0.0418},
      {"cut_effect", nullptr},
      {"reference_error_bar", {{"known", true}, {"rms_mm", 0.071}, {"method", "against the finest level"}}},
      {"versus_extrapolated",
       {{"error_bar_mm", 0.0122},
        {"solved_reference_rmse_mm", 0.0700},
        {"models",
         {{"enrichment", {{"rmse_mm", 0.1210}, {"rmse_relative_to_peak", 0.0123}}},
          {"visibility", {{"rmse_mm", 0.1265}, {"rmse_relative_to_peak", 0.0129}}}}}}},
      {"cloud_change",
       {{"known", true}, {"mm", 0.1068}, {"measure", "difference"},
        {"runs", {{{"run", "runs/a"}, {"enrichment", {{"rmse_mm", 0.0670}, {"n_nodes", 12217}}}}}}}},
      {"cloud_change_versus_extrapolated",
       {{"known", true}, {"mm", 0.0562}, {"measure", "difference"},
        {"runs", {{{"run", "runs/a"}, {"enrichment", {{"rmse_mm", 0.0711}, {"n_nodes", 12217}}}},
                  {{"run", "runs/old"}, {"unused", "no RMSEs against the extrapolated FEM"}}}}}},
      {"paper_enrichment_mm", 4.04},
      {"paper_visibility_mm", 8.03},
      {"paper_difference_mm", -3.99}};
  nlohmann::json small = cut;
  small["label"] = "small";
  small["models"] = {enrichment, {{"name", "lrpim"}, {"role", "Fig. 9 baseline: LRPIM"}, {"not_solved", "no cut"}}};
  small["difference_mm"] = nullptr;
  small["versus_extrapolated"] = nullptr;
  small.erase("cloud_change");
  small.erase("cloud_change_versus_extrapolated");
  const std::string md = experiments::table1_md(nlohmann::json::array({small, cut}));
  const auto has = [&](const std::string& text) { return md.find(text) != std::string::npos; };
  EXPECT_TRUE(has("| against the extrapolated FEM [mm] |")) << md;
  EXPECT_TRUE(has("enrichment 0.1210 (1.2 %), visibility 0.1265 (1.3 %); their bar 0.0122 mm; the solved reference "
                  "0.0700 mm from them"))
      << md;
  EXPECT_TRUE(has("| 0.1068 (difference); against the extrapolated FEM 0.0562 (difference) |")) << md;
  // 0.0055 / hypot(0.0122, 0.0562) = 0.096: below 0.1, two decimals.
  EXPECT_TRUE(has("0.10× their bar and the cloud change against them combined: not significant")) << md;
  EXPECT_TRUE(has("cutting: the meshless cloud change against the extrapolated FEM, from the kept runs of its cloud "
                  "studies:\n- runs/a: enrichment 0.0711 mm (12217 nodes)\n- runs/old: unused, no RMSEs against "
                  "the extrapolated FEM"))
      << md;
  EXPECT_TRUE(has("| small | 0.1021 (1.0 %) | not solved |")) << md;
  EXPECT_TRUE(has("small, lrpim: no cut.")) << md;
  // Every row has as many cells as the header.
  std::size_t header_cells = 0, row_cells = 0;
  std::istringstream lines(md);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("| case |", 0) == 0) header_cells = std::count(line.begin(), line.end(), '|');
    if (line.rfind("| cutting |", 0) == 0) row_cells = std::count(line.begin(), line.end(), '|');
  }
  EXPECT_GT(header_cells, 10u);
  EXPECT_EQ(row_cells, header_cells) << md;
}

// The side-by-side Table 1 hands each child the compare options the cases get in this process: a dropped flag would
// silently change a case's error bar (--reference-family) or draw plots a --no-plot run does not want.
TEST(ReproducePlan, TheChildsCompareCommandLineCarriesTheCasesOptions) {
  experiments::CompareOptions compare;
  compare.out_dir = "/tmp/out/cutting";
  compare.plot = false;
  compare.reference_family = {"/a/fem.json", "/b/fem.json"};
  EXPECT_EQ(experiments::compare_command_line("/bin/tissue", "/c/lung_large.json", compare),
            (std::vector<std::string>{"/bin/tissue", "compare", "/c/lung_large.json", "--out", "/tmp/out/cutting",
                                      "--no-plot", "--reference-family", "/a/fem.json", "--reference-family",
                                      "/b/fem.json"}));
  compare.plot = true;
  compare.reference_family.clear();
  EXPECT_EQ(experiments::compare_command_line("tissue", "x.json", compare),
            (std::vector<std::string>{"tissue", "compare", "x.json", "--out", "/tmp/out/cutting"}));
  // The other options keep compare's defaults, which reproduce does not change: the command line is complete only
  // while that holds.
  const experiments::CompareOptions defaults;
  EXPECT_EQ(defaults.reference_samples, "solved");
  EXPECT_TRUE(defaults.cut_effect);
  EXPECT_EQ(defaults.reference_error_file, "results/verify/fem.json");
  EXPECT_TRUE(defaults.externals.empty());
  EXPECT_FALSE(defaults.patch_edge_distance.has_value());
  EXPECT_FALSE(defaults.cut_distance.has_value());
}
