// `tissue reproduce`: the plan file is checked before anything runs, and the shipped plan is the paper's.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <algorithm>
#include <nlohmann/json.hpp>

#include "core/case.hpp"
#include "core/case_error.hpp"
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

  const std::string not_json = write_plan("not_json", "{\"table1\": [");
  EXPECT_NE(error_of(not_json).find("valid JSON"), std::string::npos) << error_of(not_json);
}
